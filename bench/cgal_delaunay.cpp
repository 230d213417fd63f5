// The peer for `fractalbake bench --generator terrain`: CGAL's Delaunay_triangulation_2 (exact
// predicates, inexact constructions) building from the same 10^6 uniform random points, inserted as
// a range (CGAL sorts them spatially first: hilbert_sort with BRIO-like randomisation). Prints one
// JSON line like fractalbake's. Built and run by bench/run.sh when libcgal-dev is installed; never
// part of fractalbake itself.
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/version.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using DT = CGAL::Delaunay_triangulation_2<K>;

// the same generator as fb_bench_splitmix64 (host/core/benchkit.c)
static uint64_t splitmix64(uint64_t &s)
{
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double unit_of(uint64_t &s)
{
    return (double)(splitmix64(s) >> 11) * 0x1.0p-53;
}

int main(int argc, char **argv)
{
    bool json = argc > 1 && !std::strcmp(argv[1], "--json");
    const size_t n = 1000000;
    std::vector<K::Point_2> pts;
    pts.reserve(n);
    uint64_t seed = 1;
    std::vector<double> xy(2 * n);
    for (auto &v : xy) v = unit_of(seed);
    for (size_t i = 0; i < n; i++) pts.emplace_back(xy[2 * i], xy[2 * i + 1]);
    double w[3];
    size_t faces = 0;
    for (int i = -1; i < 3; i++) {
        auto t0 = std::chrono::steady_clock::now();
        DT dt;
        dt.insert(pts.begin(), pts.end());
        double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        faces = dt.number_of_faces();
        if (i >= 0) w[i] = sec;
    }
    std::sort(w, w + 3);
    double rate = (double)n / w[1] * 1e-6;
    if (json)
        std::printf("{\"generator\": \"delaunay\", \"backend\": \"native\", \"device\": \"CGAL %s "
                    "Delaunay_triangulation_2\", \"mode\": \"build-1e6-uniform\", \"unit\": \"Minserts/s\", "
                    "\"rate\": %.3f, \"inserts\": %zu, \"seconds\": %.3f, \"threads\": 1, \"faces\": %zu}\n",
                    CGAL_VERSION_STR, rate, n, w[1], faces);
    else
        std::printf("delaunay native  build-1e6-uniform      %8.3f Minserts/s  (%zu inserts in %.3f s)  [CGAL %s, 1 "
                    "thread; %zu faces]\n",
                    rate, n, w[1], CGAL_VERSION_STR, faces);
    return 0;
}
