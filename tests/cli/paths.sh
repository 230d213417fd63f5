#!/usr/bin/env bash
# File names in a scene: relative to the scene file's folder (inputs and the files a layer writes),
# to the working folder on the command line (flags, --set, a scene on stdin) and in a stored scene
# (--from), which holds them joined to the folder they were read from. Usage: paths.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native --quiet"
same() { "$FB" compare "$1" "$2" > /dev/null; }

# the gallery's range from the repository's root and from here (relative and absolute): the same pixels
rel=$(realpath --relative-to="$T" "$ROOT/docs/examples/gallery-rivers.json")
(cd "$ROOT" && "$FB" render docs/examples/gallery-rivers.json --set size=96x96 --set layers.range.steps=20 -o "$T/root.exr" $N) &&
  ok || bad "gallery-rivers.json from the repository's root failed"
"$FB" render "$rel" --set size=96x96 --set layers.range.steps=20 -o here.exr $N 2> err.txt &&
  ok || bad "gallery-rivers.json from another folder ($rel) failed: $(cat err.txt)"
"$FB" render "$ROOT/docs/examples/gallery-rivers.json" --set size=96x96 --set layers.range.steps=20 -o abs.exr $N &&
  ok || bad "gallery-rivers.json by its absolute path failed"
check "the same pixels from the root and from another folder" same root.exr here.exr
check "the same pixels by an absolute path" same root.exr abs.exr

# a scene in a folder of its own: its points beside it, a heightmap written beside it
mkdir -p sub/deep work
printf 'x,y,z\n0,0,0\n100,0,10\n0,100,20\n100,100,5\n50,50,40\n' > sub/pts.csv
printf 'x,y,z\n0,0,0\n100,0,50\n0,100,0\n100,100,50\n50,50,0\n' > work/other.csv
printf '{"size": [32, 32], "layers": [{"type": "terrain", "name": "t", "points": "pts.csv", "insert": 50, "heightmap": "h.png"}]}' > sub/s.json
(cd work && "$FB" render ../sub/s.json -o s.exr $N 2> err.txt) && ok || bad "a scene's points beside it: $(cat work/err.txt)"
check "the scene's heightmap is written beside the scene" test -s sub/h.png
check "and not into the working folder" test ! -e work/h.png
# the same scene from its own folder: the same pixels
(cd sub && "$FB" render s.json -o ../own.exr $N --set layers.t.heightmap=h2.png) && ok || bad "the scene from its own folder failed"
check "a scene from its own folder and from another: the same pixels" same own.exr work/s.exr
# --set: the working folder's file
(cd work && "$FB" render ../sub/s.json --set layers.t.points=other.csv --set layers.t.heightmap=h3.png -o s2.exr $N) &&
  ok || bad "--set points: the working folder's file"
check "--set's heightmap is written into the working folder" test -s work/h3.png
same work/s.exr work/s2.exr && bad "--set points= read the scene's file, not the working folder's" || ok
# the stored scene holds the joined names: --from from the same folder bakes the same pixels
(cd work && "$FB" render --from s.exr -o from.exr $N 2> err.txt) && ok || bad "--from a scene read from another folder: $(cat work/err.txt)"
check "--from: the same pixels" same work/s.exr work/from.exr
"$FB" info work/s.exr | grep -q '"points": "../sub/pts.csv"' && ok || bad "the stored scene lacks the joined name ../sub/pts.csv"
# a scene on stdin: the working folder
sed 's#"pts.csv"#"sub/pts.csv"#; s#"h.png"#"h4.png"#' sub/s.json | "$FB" render - -o stdin.exr $N && ok || bad "a scene on stdin"
check "a scene on stdin reads its points from the working folder: the same pixels" same stdin.exr work/s.exr
check "a scene on stdin writes its heightmap into the working folder" test -s h4.png
# a missing file is named as the scene resolves it, relative to the working folder
printf '{"size": [32, 32], "layers": [{"type": "terrain", "points": "none.csv"}]}' > sub/deep/m.json
(cd work && expect_fail 2 '^fractalbake: layer terrain: \.\./sub/deep/none\.csv: cannot open points' o.exr -- render ../sub/deep/m.json -o o.exr $N)
# names that are not files stay as they are: a constrain layer's macro from a layer, an absolute path
printf '{"size": [32, 32], "layers": [{"type": "fbm", "name": "hill"}, {"type": "constrain", "macro": "hill", "points": [[4, 4]]}, {"type": "terrain", "name": "abs", "points": "%s"}]}' "$T/sub/pts.csv" > sub/deep/c.json
(cd work && "$FB" render ../sub/deep/c.json -o c.exr $N 2> err.txt) && ok || bad "a macro layer and an absolute path in a scene: $(cat work/err.txt)"
# a stored scene with an instances file: --from drops the file and the keys that only say how to write it
printf '{"size": [48, 32], "layers": [{"type": "fbm", "name": "g"}, {"type": "ifs", "name": "p", "preset": "population", "points": 20000, "instances": "p.csv", "instances-surface": "g", "instances-min-size": 0.5}]}' > sub/i.json
(cd work && "$FB" render ../sub/i.json -o i.exr $N) && ok || bad "a scene with instances failed"
check "the scene's instances are written beside it" test -s sub/p.csv
(cd work && "$FB" render --from i.exr -o i2.exr --backend native 2> err.txt) && ok || bad "--from a file with instances: $(cat work/err.txt)"
check "--from a file with instances: the same pixels" same work/i.exr work/i2.exr
check "--from says it dropped the instances, with the keys that only say how to write them" grep -q "not writing the stored scene's outputs (layers.p.instances=../sub/p.csv with its instances-" work/err.txt
cli_finish
