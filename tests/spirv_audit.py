#!/usr/bin/env python3
"""The SPIR-V audit: every embedded shader computes its outputs with operations that a conformant
Vulkan device must round exactly as the native C path does.

    spirv_audit.py SPV_DIR            audit every NAME.spv of the build (build/spv)
    spirv_audit.py --self-test BUILD  also show that it fails on planted violations

What a device may do differently (the Vulkan specification's SPIR-V environment, "Precision and
Operation of SPIR-V Instructions"), and what the audit demands instead:
- fuse or rearrange float operations not decorated NoContraction: every float arithmetic result
  carries NoContraction (cmake/spvexact.c adds it at build time);
- OpFDiv to 2.5 ulp, sqrt and the transcendentals to their own bounds, OpFRem/OpFMod, dot products
  and matrix products "inherited" in any order, fma fused or not, mix and smoothstep rearranged:
  none of these outside the exact helpers of kernels/exact.h, which correct the device's estimate
  exactly (the functions that header defines, by name: a function merely named kx_something is not
  one of them);
- FMin/FMax/FClamp undefined on NaN: NMin/NMax/NClamp instead (spvexact renames them);
- OpQuantizeToF16, packHalf2x16 and the pack/unpack *norm* family, Round (its halfway direction is
  the implementation's), Determinant and MatrixInverse (no precision required at all): never;
- RelaxedPrecision (mediump, lowp): never, the device may compute such a result in 16 bits;
- any other GLSL.std.450 instruction: only those on ALLOWED_GLSL (exact on every device) anywhere,
  those of HELPER_GLSL inside the helpers; anything else is refused until it is listed.
The ceiling_* shaders measure the device (bench), write nothing a bake keeps, and are exempt.
Exit 0 when every module passes (and spirv-val accepts it), 1 otherwise, listing each violation.
"""
import os
import re
import subprocess
import sys
import tempfile

FLOAT_ARITH = {"OpFNegate", "OpFAdd", "OpFSub", "OpFMul", "OpFDiv", "OpFRem", "OpFMod", "OpVectorTimesScalar",
               "OpMatrixTimesScalar", "OpVectorTimesMatrix", "OpMatrixTimesVector", "OpMatrixTimesMatrix",
               "OpOuterProduct", "OpDot"}
INEXACT_OPS = {"OpFDiv", "OpFRem", "OpFMod", "OpDot", "OpVectorTimesMatrix", "OpMatrixTimesVector",
               "OpMatrixTimesMatrix"}
NEVER_OPS = {"OpQuantizeToF16"}
HELPER_GLSL = {"Sqrt", "InverseSqrt", "Exp", "Exp2", "Log", "Log2", "Pow", "Sin", "Cos", "Tan", "Asin", "Acos",
                "Atan", "Atan2", "Sinh", "Cosh", "Tanh", "Asinh", "Acosh", "Atanh", "Fma", "FMix", "SmoothStep",
                "Length", "Distance", "Normalize", "Cross", "Reflect", "Refract", "FaceForward", "Radians",
                "Degrees"}
# exact on every conformant device (comparisons, integer and bit operations, sign and exponent
# manipulation, rounding in a fixed direction): allowed anywhere
ALLOWED_GLSL = {"FAbs", "SAbs", "FSign", "SSign", "Floor", "Ceil", "Trunc", "RoundEven", "NMin", "NMax", "NClamp",
                "UMin", "UMax", "SMin", "SMax", "UClamp", "SClamp", "Step", "FindILsb", "FindSMsb", "FindUMsb",
                "PackDouble2x32", "UnpackDouble2x32"}
NEVER_GLSL = {"FMin": "undefined on NaN", "FMax": "undefined on NaN", "FClamp": "undefined on NaN",
              "Round": "its halfway direction is the implementation's",
              "Determinant": "no precision required", "MatrixInverse": "no precision required"}
for _n in ("PackHalf2x16", "UnpackHalf2x16", "PackSnorm2x16", "PackUnorm2x16", "PackSnorm4x8", "PackUnorm4x8",
           "UnpackSnorm2x16", "UnpackUnorm2x16", "UnpackSnorm4x8", "UnpackUnorm4x8"):
    NEVER_GLSL[_n] = "rounded or scaled to an implementation-defined precision"
EXEMPT = ("ceiling_",)
# Modules known to fail while their kernel is rewritten on a branch of its own: strict, so that the
# list must shrink the day they pass (none now: the flame's passed with issue 42's variations).
PENDING = set()
EXACT_H = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "kernels", "exact.h")


def exact_helpers(path=EXACT_H):
    """The names of the functions kernels/exact.h defines for shaders (K_FN TYPE kx_NAME(...))."""
    with open(path) as fh:
        names = set(re.findall(r"^K_FN\s+\w+\s+(kx_\w+)\s*\(", fh.read(), re.M))
    if not names:
        raise RuntimeError(f"no K_FN kx_ helper found in {path}")
    return names


HELPERS = exact_helpers()


def disassemble(path):
    out = subprocess.run(["spirv-dis", "--raw-id", "--no-color", path], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"spirv-dis {path}: {out.stderr.strip()}")
    return out.stdout.splitlines()


def audit_module(path):
    """The list of violations of one module (strings)."""
    lines = disassemble(path)
    names, no_contraction, float_types = {}, set(), set()
    bad = []
    for ln in lines:
        if re.match(r"\s*Op(Member)?Decorate .*RelaxedPrecision", ln):
            bad.append(f"RelaxedPrecision (mediump or lowp: 16 bits allowed): module: {ln.strip()}")
        m = re.match(r'\s*OpName (%\d+) "([^"]*)"', ln)
        if m:
            names[m.group(1)] = m.group(2)
        m = re.match(r"\s*OpDecorate (%\d+) NoContraction", ln)
        if m:
            no_contraction.add(m.group(1))
    func = None
    for ln in lines:
        m = re.match(r"\s*(%\d+) = OpFunction ", ln)
        if m:
            func = names.get(m.group(1), m.group(1))
            continue
        if re.match(r"\s*OpFunctionEnd", ln):
            func = None
            continue
        m = re.match(r"\s*(%\d+) = (Op\w+)(.*)", ln)
        if not m:
            continue
        rid, op, rest = m.groups()
        where = f"{func or 'module'}: {ln.strip()}"
        # glslang names a function NAME(ARGTYPES; the helper is one exact.h defines by that name
        in_helper = func is not None and func.split("(")[0] in HELPERS
        if op in FLOAT_ARITH and rid not in no_contraction:
            bad.append(f"no NoContraction: {where}")
        if op in NEVER_OPS:
            bad.append(f"implementation-defined rounding: {where}")
        if op in INEXACT_OPS and not in_helper:
            bad.append(f"inexact on a device, outside the exact helpers: {where}")
        if op == "OpExtInst":
            g = re.match(r"\s*%\d+ %\d+ (\w+)", rest)
            inst = g.group(1) if g else ""
            if inst in NEVER_GLSL:
                bad.append(f"GLSL.std.450 {inst} ({NEVER_GLSL[inst]}): {where}")
            elif inst in HELPER_GLSL:
                if not in_helper:
                    bad.append(f"GLSL.std.450 {inst} is inexact on a device, outside the exact helpers: {where}")
            elif inst not in ALLOWED_GLSL:
                bad.append(f"GLSL.std.450 {inst or rest.strip()} is not on the audit's allowed list: {where}")
    val = subprocess.run(["spirv-val", "--target-env", "vulkan1.1", path], capture_output=True, text=True)
    if val.returncode != 0:
        bad.append(f"spirv-val: {(val.stderr or val.stdout).strip()}")
    return bad


def audit_dir(spv_dir, quiet=False):
    # the portable modules, then the native variants (cmake/spvexact.c: K_EXACT_NATIVE made true)
    mods = sorted(f for f in os.listdir(spv_dir) if f.endswith(".spv") and not f.startswith(EXEMPT))
    native = os.path.join(spv_dir, "native")
    if os.path.isdir(native):
        mods += sorted("native/" + f for f in os.listdir(native) if f.endswith(".spv") and not f.startswith(EXEMPT))
    if not mods:
        print(f"spirv_audit: no modules in {spv_dir}")
        return 1
    failed = 0
    for f in mods:
        bad = audit_module(os.path.join(spv_dir, f))
        if f.startswith("native/") and any(re.search(r"SpecId 127$", ln) for ln in disassemble(os.path.join(spv_dir, f))):
            bad.append("the native variant still specialises K_EXACT_NATIVE (SpecId 127)")
        if os.path.basename(f) in PENDING:
            if not bad:
                failed += 1
                print(f"{f}: passes the audit now: take it off PENDING")
            elif not quiet:
                print(f"{f}: pending, {len(bad)} violation(s) (expected until its branch lands)")
            continue
        if bad:
            failed += 1
            if not quiet:
                print(f"{f}: {len(bad)} violation(s)")
                for b in bad[:20]:
                    print("  " + b)
                if len(bad) > 20:
                    print(f"  ... {len(bad) - 20} more")
    if not quiet:
        pend = sum(os.path.basename(f) in PENDING for f in mods)
        print(f"spirv_audit: {len(mods) - pend - failed} of {len(mods) - pend} modules exact"
              + (f" ({pend} pending)" if pend else ""))
    return 1 if failed else 0


PLANTED = """#version 450
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer B { float v[]; } b;
float kx_div(float a, float x) { return a / x; }  // a helper of kernels/exact.h may divide
float kx_leak(float a, float x) { return a / x; } // a name like a helper's is not one
void main() {
    uint i = gl_GlobalInvocationID.x;
    float x = b.v[i];
    %s
    b.v[i] = kx_div(1.0, x) + %s;
}
"""

# name, a declaration, the planted expression, spvexact applied, the audit's expected verdict
PLANTS = [("clean", "", "x * 2.0", True, True), ("exact-ops", "", "floor(x) + abs(x) + roundEven(x)", True, True),
          ("division", "", "x / 3.0", True, False), ("sqrt", "", "sqrt(x)", True, False),
          ("fmin", "", "min(x, 1.0)", True, True), ("dot", "", "dot(vec2(x), vec2(x, 1.0))", True, False),
          ("fma", "", "fma(x, x, 1.0)", True, False), ("contraction", "", "x * x + 1.0", False, False),
          ("fmin-raw", "", "min(x, 1.0)", False, False), ("round", "", "round(x)", True, False),
          ("mediump", "mediump float m = x * 3.0;", "m", True, False),
          ("unpackUnorm", "", "unpackUnorm4x8(floatBitsToUint(x)).y", True, False),
          ("unpackSnorm", "", "unpackSnorm2x16(floatBitsToUint(x)).x", True, False),
          ("determinant", "", "determinant(mat2(x, 1.0, 2.0, x))", True, False),
          ("inverse", "", "inverse(mat2(x, 1.0, 2.0, x))[0][0]", True, False),
          ("unlisted", "", "fract(x)", True, False), ("kx_leak", "", "kx_leak(1.0, x)", True, False)]


def self_test(build):
    """The audit fails on each planted violation and passes on the clean controls."""
    spvexact = os.path.join(build, "spvexact")
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        for name, decl, expr, patched, want_pass in PLANTS:
            src = os.path.join(tmp, f"{name}.comp")
            with open(src, "w") as fh:
                fh.write(PLANTED % (decl, expr))
            raw = os.path.join(tmp, f"{name}.raw.spv")
            subprocess.run(["glslangValidator", "-V", "--target-env", "vulkan1.1", "--quiet", "-o", raw, src],
                           check=True)
            spv = os.path.join(tmp, f"{name}.spv")
            if patched:
                subprocess.run([spvexact, raw, spv, os.path.join(tmp, f"{name}.native.spv")], check=True)
            else:
                os.rename(raw, spv)
            bad = audit_module(spv)
            passed = not bad
            verdict = "ok" if passed == want_pass else "WRONG"
            print(f"planted {name:12s} {'patched' if patched else 'raw    '}: audit "
                  f"{'passes' if passed else 'fails'} ({len(bad)}), expected {'pass' if want_pass else 'fail'}: {verdict}"
                  + (f" [{bad[0][:90]}]" if bad and not want_pass else ""))
            ok = ok and passed == want_pass
    return ok


def main():
    args = sys.argv[1:]
    if len(args) == 2 and args[0] == "--self-test":
        build = args[1]
        ok = self_test(build)
        rc = audit_dir(os.path.join(build, "spv"))
        return 0 if ok and rc == 0 else 1
    if len(args) != 1:
        print(__doc__.splitlines()[2], file=sys.stderr)
        return 2
    return audit_dir(args[0])


if __name__ == "__main__":
    sys.exit(main())
