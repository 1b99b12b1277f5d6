#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Independent reference implementation of the SHaRC hash grid (cache_format/SPEC.md "Hash grid").

Written from the algorithm description only (shared/reference/sharc_algorithm.md §2 and SPEC.md),
not from the C++ sources, so that the two implementations cross-check each other. Pure stdlib:
binary32 arithmetic is emulated by rounding every intermediate result through struct 'f'
(double has more than 2*24+2 mantissa bits, so + - * / computed in double and rounded once to
float are exactly the IEEE binary32 results).

Usage:
  hash_grid_vectors.py                     print the test-vector table (Markdown) to stdout
  hash_grid_vectors.py --update            rewrite the table in cache_format/SPEC.md and the C++
                                           include tests/cache_format/hash_grid_vectors.inc
  hash_grid_vectors.py --check [--dump-exe EXE] [--random N]
                                           verify that SPEC.md and the .inc hold exactly what this
                                           script computes, and (with EXE) that the C++ library
                                           computes the same level/cell/key/hash/slots/voxel
                                           size/debug colour/voxel centre for every vector and N
                                           random and adversarial cases.  Exit status 0 = agree.
"""

import argparse
import decimal
import math
import os
import random
import struct
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
SPEC_PATH = os.path.join(ROOT, "cache_format", "SPEC.md")
INC_PATH = os.path.join(HERE, "hash_grid_vectors.inc")
BEGIN_MARK = "<!-- BEGIN GENERATED HASH GRID VECTORS (tests/cache_format/hash_grid_vectors.py) -->"
END_MARK = "<!-- END GENERATED HASH GRID VECTORS -->"

LARGE_CAPACITY = 1 << 22
SMALL_CAPACITY = 1000  # deliberately not a power of two
BUCKET = 16

# ---------------------------------------------------------------------------------------------
# binary32 emulation
# ---------------------------------------------------------------------------------------------
_F32_OVERFLOW = float.fromhex("0x1.ffffffp127")  # midpoint between FLT_MAX and 2**128


def f32(x):
    """Round a Python float (double) to the nearest binary32 value (ties to even)."""
    if x != x:
        return x
    if x >= _F32_OVERFLOW:
        return math.inf
    if x <= -_F32_OVERFLOW:
        return -math.inf
    return struct.unpack("<f", struct.pack("<f", x))[0]


def bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def from_bits(u):
    return struct.unpack("<f", struct.pack("<I", u))[0]


def fadd(a, b):
    return f32(a + b)


def fsub(a, b):
    return f32(a - b)


def fmul(a, b):
    if (math.isinf(a) and b == 0) or (math.isinf(b) and a == 0):
        return math.nan
    return f32(a * b)


def fdiv(a, b):
    if a != a or b != b:
        return math.nan
    if b == 0:
        if a == 0:
            return math.nan
        neg = (math.copysign(1.0, a) < 0) != (math.copysign(1.0, b) < 0)
        return -math.inf if neg else math.inf
    if math.isinf(a) and math.isinf(b):
        return math.nan
    return f32(a / b)


def flog2(x):
    """binary32 log2: the correctly rounded float of log2(x) (via double)."""
    if x != x or x < 0:
        return math.nan
    if x == 0:
        return -math.inf
    if math.isinf(x):
        return math.inf
    return f32(math.log2(x))


def fexp2(y):
    if y != y:
        return math.nan
    if y > 1000:
        return math.inf
    if y < -1000:
        return 0.0
    e = math.exp2(y) if hasattr(math, "exp2") else 2.0 ** y
    return f32(e)


def fpow(x, y):
    # HLSL pow(x, y) as lowered to DXIL: exp2(y * log2(x)).
    return fexp2(fmul(y, flog2(x)))


def hlsl_max(a, b):  # IEEE maxNum: a NaN operand yields the other one
    if a != a:
        return b
    if b != b:
        return a
    return a if a >= b else b


def hlsl_min(a, b):
    if a != a:
        return b
    if b != b:
        return a
    return a if a <= b else b


def f2i_saturate(x):
    if x != x:
        return 0
    if x <= -2147483648.0:
        return -2147483648
    if x >= 2147483648.0:
        return 2147483647
    return int(x)  # truncation toward zero


def ffloor(x):
    if x != x or math.isinf(x):
        return x
    return float(math.floor(x))


# ---------------------------------------------------------------------------------------------
# The hash grid, step by step as in SPEC §H.2 - §H.8
# ---------------------------------------------------------------------------------------------
POSITION_BIAS = f32(1e-4)
NORMAL_BIAS = f32(1e-3)
MIN_DIST2 = f32(1e-10)
LEVEL_MAX = 511


class Params:
    def __init__(self, camera=(0.0, 0.0, 0.0), base=2.0, scale=50.0, bias=0.0):
        self.camera = tuple(f32(v) for v in camera)
        self.base = f32(base)
        self.scale = f32(scale)
        self.bias = f32(bias)

    def is_default(self):
        return self.base == 2.0 and self.scale == 50.0 and self.bias == 0.0


def level_of(p, prm):
    dx = fsub(prm.camera[0], p[0])
    dy = fsub(prm.camera[1], p[1])
    dz = fsub(prm.camera[2], p[2])
    d2 = fadd(fadd(fmul(dx, dx), fmul(dy, dy)), fmul(dz, dz))
    d2 = hlsl_max(d2, MIN_DIST2)
    ell = fadd(fmul(0.5, fdiv(flog2(d2), flog2(prm.base))), prm.bias)
    ell = hlsl_min(hlsl_max(ell, 1.0), float(LEVEL_MAX))
    return int(ell)


def voxel_size_of(level, prm):
    return fdiv(fpow(prm.base, float(level)), fmul(prm.scale, fpow(prm.base, prm.bias)))


def cell_of(p, prm):
    pb = tuple(fadd(v, POSITION_BIAS) for v in p)
    level = level_of(pb, prm)
    s = voxel_size_of(level, prm)
    g = tuple(f2i_saturate(ffloor(fdiv(v, s))) for v in pb)
    return level, g, s


def normal_bits_of(n):
    out = 0
    for i, v in enumerate(n):
        if not (fadd(v, NORMAL_BIAS) >= 0.0):  # NaN sets the bit
            out |= 1 << i
    return out


def pack(g, level, nbits):
    key = 0
    for i, v in enumerate(g):
        key |= (v & 0x1FFFF) << (17 * i)
    key |= (level & 0x1FF) << 51
    key |= (nbits & 7) << 60
    return key


def jenkins(a):
    m = 0xFFFFFFFF
    a = ((a + 0x7ED55D16) + (a << 12)) & m
    a = ((a ^ 0xC761C23C) ^ (a >> 19)) & m
    a = ((a + 0x165667B1) + (a << 5)) & m
    a = ((a + 0xD3A2646C) ^ (a << 9)) & m
    a = ((a + 0xFD7046C5) + (a << 3)) & m
    a = ((a ^ 0xB55A4F09) ^ (a >> 16)) & m
    return a


def hash32(key):
    return jenkins(key & 0xFFFFFFFF) ^ jenkins(key >> 32)


def base_slot(h, capacity):
    if capacity == 0:
        return 0xFFFFFFFF
    window = min(BUCKET, capacity)
    return min(h % capacity, capacity - window)


def sign17(v):
    v &= 0x1FFFF
    return v - 0x20000 if v & 0x10000 else v


def debug_color(key):
    def palette(h):
        return (fdiv(float(h & 0x3FF), 1023.0), fdiv(float((h >> 11) & 0x7FF), 2047.0),
                fdiv(float((h >> 22) & 0x7FF), 2047.0))
    a = palette(hash32(key))
    b = palette(jenkins((key >> 51) & 0x1FF))
    return tuple(fmul(x, y) for x, y in zip(a, b))


def voxel_center(key, prm):
    level = (key >> 51) & 0x1FF
    s = voxel_size_of(level, prm)
    return tuple(fmul(fadd(float(sign17(key >> (17 * i))), 0.5), s) for i in range(3))


def evaluate(p, n, prm, small_capacity=SMALL_CAPACITY):
    level, g, s = cell_of(p, prm)
    key = pack(g, level, normal_bits_of(n))
    h = hash32(key)
    return {
        "level": level, "grid": g, "key": key, "hash": h, "voxel": s,
        "slot_large": base_slot(h, LARGE_CAPACITY), "slot_small": base_slot(h, small_capacity),
        "color": debug_color(key), "center": voxel_center(key, prm),
    }


# ---------------------------------------------------------------------------------------------
# The published vectors
# ---------------------------------------------------------------------------------------------
NAN = math.nan


def V(name, p, n, camera=(0, 0, 0), base=2.0, scale=50.0, bias=0.0):
    return {"name": name, "p": tuple(f32(v) for v in p), "n": tuple(f32(v) for v in n),
            "prm": Params(camera, base, scale, bias)}


VECTORS = [
    V("basic", (1.0, 2.0, 3.0), (0.0, 1.0, 0.0)),
    V("negative coordinates", (-1.25, -0.5, -3.75), (0.0, 0.0, -1.0)),
    V("camera offset, level 6", (100.5, 20.25, -40.0), (1.0, 0.0, 0.0), camera=(1, 2, 3)),
    V("d = 1000, level 9", (1000.0, 0.0, 0.0), (-1.0, 0.0, 0.0)),
    V("biased point on camera: d2 = 0 -> 1e-10 -> level 1", (-1e-4, -1e-4, -1e-4),
      (0.0, 0.0, 1.0)),
    V("level boundary d = 4: below", (3.9998, 0.0, 0.0), (0.0, 1.0, 0.0)),
    V("level boundary d = 4: p' = 4 exactly", (3.9999, 0.0, 0.0), (0.0, 1.0, 0.0)),
    V("level boundary d = 4: above", (4.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    V("level clamped at min (bias -5)", (10.0, 0.0, 0.0), (0.0, 1.0, 0.0), bias=-5.0),
    V("level clamped at max (base 1.01)", (1000.0, -3.5, 2.25), (0.0, 1.0, 0.0), base=1.01),
    V("d2 overflows to inf: level 511, voxel inf", (3e19, 0.0, 0.0), (0.0, 1.0, 0.0)),
    V("normal all +0", (0.5, 0.5, 0.5), (0.0, 0.0, 0.0)),
    V("normal all -0", (0.5, 0.5, 0.5), (-0.0, -0.0, -0.0)),
    V("normal at -bias: -1e-3, -9e-4, -1.1e-3", (0.5, 0.5, 0.5), (-1e-3, -9e-4, -1.1e-3)),
    V("normal all negative", (0.5, 0.5, 0.5), (-0.57735, -0.57735, -0.57735)),
    V("normal NaN x (SDK: NaN sets the bit)", (0.5, 0.5, 0.5), (NAN, 0.0, 1.0)),
    V("17-bit wrap: x=65535, y=-65537, z=131072", (2621.42, -2621.46, 5242.9), (0.0, 0.0, 1.0),
      camera=(2621.0, -2621.0, 5243.0)),
    V("far from origin (float precision)", (100000.3, -250000.7, 4.5), (0.0, -1.0, 0.0),
      camera=(99990.0, -250010.0, 0.0)),
    V("base 4, scale 10, bias 1.5", (7.3, -2.2, 15.9), (0.6, -0.8, 0.0), camera=(1, 1, 1),
      base=4.0, scale=10.0, bias=1.5),
    V("base 3 (not a power of two)", (50.0, 60.0, -70.0), (0.0, 0.0, -1.0), base=3.0),
    V("NaN position: level 1, cell 0", (NAN, 1.0, 2.0), (0.0, 1.0, 0.0)),
    # Found with --search-near-end: slots clamped to the last bucket window.
    V("small N: hash % 1000 > 984 -> base 984", (0.06, 0.06, 1.02), (0.0, 1.0, 0.0)),
    V("N = 2^22: hash % N > N - 16 -> base N - 16", (0.78, 2.74, 2.18), (0.0, 1.0, 0.0)),
]


def short_float(x):
    """Shortest decimal that round-trips to the same binary32 value."""
    if x != x:
        return "NaN"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x == 0:
        return "-0" if math.copysign(1.0, x) < 0 else "0"
    for digits in range(1, 10):
        s = "%.*g" % (digits, x)
        if f32(float(s)) == x:
            break
    if 1e-5 <= abs(x) < 1e7:  # plain notation for everyday magnitudes
        s = format(decimal.Decimal(s), "f")
    return s.replace("e+", "e")


def vec_str(v):
    return "(" + ", ".join(short_float(c) for c in v) + ")"


def markdown_table():
    lines = [
        BEGIN_MARK,
        "",
        "Defaults unless stated: camera (0, 0, 0), b = 2, S = 50, beta = 0. All inputs are binary32",
        "values (shown as the shortest decimal that rounds to them). Slot columns: "
        "`base` for N = 2^22 and for N = %d." % SMALL_CAPACITY,
        "",
        "| # | case | position | normal | camera; b, S, beta | level | grid (x, y, z), unmasked | key | hash "
        "| base N=2^22 | base N=%d |" % SMALL_CAPACITY,
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for i, vec in enumerate(VECTORS):
        prm = vec["prm"]
        r = evaluate(vec["p"], vec["n"], prm)
        pstr = vec_str(prm.camera)
        if not prm.is_default():
            pstr += "; %s, %s, %s" % (short_float(prm.base), short_float(prm.scale),
                                      short_float(prm.bias))
        lines.append("| %d | %s | %s | %s | %s | %d | %s | `0x%016X` | `0x%08X` | %d | %d |" % (
            i + 1, vec["name"], vec_str(vec["p"]), vec_str(vec["n"]), pstr, r["level"],
            "(%d, %d, %d)" % r["grid"], r["key"], r["hash"], r["slot_large"], r["slot_small"]))
    lines += ["", END_MARK]
    return "\n".join(lines)


def jenkins_table():
    return [(v, jenkins(v)) for v in (0, 1, 2, 0x7FFFFFFF, 0x80000000, 0xDEADBEEF, 0xFFFFFFFF)]


def inc_text():
    out = ["// SPDX-License-Identifier: Apache-2.0",
           "// GENERATED by tests/cache_format/hash_grid_vectors.py --update. Do not edit by hand.",
           "// Inputs are binary32 bit patterns; see cache_format/SPEC.md \"Test vectors\".",
           "constexpr uint32_t kVectorSmallCapacity = %du;" % SMALL_CAPACITY,
           "constexpr HashGridVector kHashGridVectors[] = {"]
    for vec in VECTORS:
        prm = vec["prm"]
        r = evaluate(vec["p"], vec["n"], prm)
        fb = lambda t: "{" + ", ".join("0x%08Xu" % bits(c) for c in t) + "}"
        out.append('    {"%s", %s, %s, %s, 0x%08Xu, 0x%08Xu, 0x%08Xu, %du, {%d, %d, %d}, '
                   '0x%016Xull, 0x%08Xu, %du, %du, 0x%08Xu},' % (
                       vec["name"], fb(vec["p"]), fb(vec["n"]), fb(prm.camera), bits(prm.base),
                       bits(prm.scale), bits(prm.bias), r["level"], r["grid"][0], r["grid"][1],
                       r["grid"][2], r["key"], r["hash"], r["slot_large"], r["slot_small"],
                       bits(r["voxel"])))
    out.append("};")
    out.append("constexpr uint32_t kJenkinsVectors[][2] = {")
    for a, b in jenkins_table():
        out.append("    {0x%08Xu, 0x%08Xu}," % (a, b))
    out.append("};")
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------------------------------
# Random and adversarial cases for the C++ cross-check
# ---------------------------------------------------------------------------------------------
def random_cases(count, seed=20240611):
    rng = random.Random(seed)
    cases = []
    for vec in VECTORS:
        cases.append((vec["p"], vec["n"], vec["prm"], SMALL_CAPACITY))
    normals = [0.0, -0.0, 1.0, -1.0, f32(-1e-3), f32(-9.9e-4), f32(-1.01e-3), 0.5, -0.5]
    for i in range(count):
        kind = i % 6
        base = rng.choice([2.0, 2.0, 2.0, 4.0, 1.5, 3.0, 10.0, 1.01])
        scale = rng.choice([50.0, 50.0, 5.0, 100.0, 0.5, 1234.5, rng.uniform(0.1, 500)])
        bias = rng.choice([0.0, 0.0, 1.0, -2.0, 0.5, rng.uniform(-6, 6)])
        camera = tuple(rng.choice([0.0, rng.uniform(-100, 100), rng.uniform(-1e5, 1e5)])
                       for _ in range(3))
        prm = Params(camera, base, scale, bias)
        if kind == 0:  # uniform in a room around the camera
            p = tuple(f32(c + rng.uniform(-50, 50)) for c in prm.camera)
        elif kind == 1:  # wide range of magnitudes and signs
            p = tuple(f32(rng.choice([-1, 1]) * 10 ** rng.uniform(-6, 7)) for _ in range(3))
        elif kind == 2:  # exactly on / a few ulps around a cell boundary (before the bias)
            lvl, _, s = cell_of(prm.camera, prm)
            p = []
            for _ in range(3):
                k = rng.randint(-70000, 70000)
                v = f32(fmul(float(k), s) - POSITION_BIAS)
                for _ in range(rng.randint(-3, 3) % 4):
                    v = from_bits(bits(v) + rng.choice([-1, 1])) if v != 0 else v
                p.append(v)
            p = tuple(p)
        elif kind == 3:  # around a level boundary along one axis: |c - p'| near b^k
            k = rng.randint(-3, 20)
            d = f32(prm.base ** k) if prm.base ** k < 1e30 else f32(1e30)
            axis = rng.randint(0, 2)
            p = list(prm.camera)
            v = fsub(fadd(p[axis], d), POSITION_BIAS)
            v = from_bits(max(0, bits(v) + rng.randint(-2, 2))) if v > 0 else v
            p[axis] = v
            p = tuple(p)
        elif kind == 4:  # camera and point next to the 17-bit wrap of the level-1 grid
            s1 = voxel_size_of(1, prm)
            k = rng.choice([65535, 65536, -65536, -65537, 131071, 131072])
            prm = Params(tuple(f32(fmul(float(k), s1) + rng.uniform(-0.5, 0.5) * s1)
                               for _ in range(3)), base, scale, bias)
            p = tuple(f32(c + rng.uniform(-1.5, 1.5) * s1) for c in prm.camera)
        else:  # special values
            pool = [0.0, -0.0, math.inf, -math.inf, math.nan, 3.4e38, -3.4e38, 1e-45, -1e-45]
            p = tuple(f32(rng.choice(pool + [rng.uniform(-10, 10)])) for _ in range(3))
        n = tuple(rng.choice(normals + [f32(rng.uniform(-1, 1)), math.nan]) for _ in range(3))
        capacity = rng.choice([1, 5, 15, 16, 17, 1000, 4095, 1 << 22, rng.randint(1, 1 << 30)])
        cases.append((p, n, prm, capacity))
    return cases


def run_dump(exe, cases):
    lines = []
    for p, n, prm, cap in cases:
        vals = list(p) + list(n) + list(prm.camera) + [prm.base, prm.scale, prm.bias]
        lines.append(" ".join("%08x" % bits(v) for v in vals) + " %d" % cap)
    proc = subprocess.run([exe], input="\n".join(lines) + "\n", capture_output=True, text=True,
                          check=False)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        raise SystemExit("dump executable failed with status %d" % proc.returncode)
    return proc.stdout.splitlines()


def expected_dump_line(p, n, prm, cap):
    r = evaluate(p, n, prm, cap)
    fields = [str(r["level"])] + [str(v) for v in r["grid"]] + [
        "%016x" % r["key"], "%08x" % r["hash"], str(r["slot_small"]), "%08x" % bits(r["voxel"])]
    fields += ["%08x" % bits(v) for v in r["color"]]
    fields += ["%08x" % bits(v) for v in r["center"]]
    return " ".join(fields)


def same_float_field(a, b):
    # NaN payloads are not specified: any NaN matches any NaN.
    fa, fb = from_bits(int(a, 16)), from_bits(int(b, 16))
    return a == b or (fa != fa and fb != fb)


def check(args):
    failures = 0
    spec = open(SPEC_PATH, encoding="utf-8").read()
    table = markdown_table()
    if table not in spec:
        print("FAIL: the test-vector table in %s differs from this script's output "
              "(run with --update after reviewing the change)" % SPEC_PATH)
        failures += 1
    else:
        print("ok: SPEC.md test-vector table matches (%d vectors)" % len(VECTORS))
    if open(INC_PATH, encoding="utf-8").read() != inc_text():
        print("FAIL: %s differs from this script's output" % INC_PATH)
        failures += 1
    else:
        print("ok: hash_grid_vectors.inc matches")
    if args.dump_exe:
        cases = random_cases(args.random)
        got = run_dump(args.dump_exe, cases)
        if len(got) != len(cases):
            print("FAIL: dump printed %d lines for %d cases" % (len(got), len(cases)))
            return 1
        mismatches = 0
        for (p, n, prm, cap), line in zip(cases, got):
            want = expected_dump_line(p, n, prm, cap)
            wf, gf = want.split(), line.split()
            ok = len(wf) == len(gf) and all(
                w == g if i < 8 else same_float_field(w, g) for i, (w, g) in enumerate(zip(wf, gf)))
            if not ok:
                mismatches += 1
                if mismatches <= 10:
                    print("MISMATCH p=%s n=%s camera=%s b=%r S=%r beta=%r N=%d\n  python: %s\n  c++:    %s"
                          % (vec_str(p), vec_str(n), vec_str(prm.camera), prm.base, prm.scale,
                             prm.bias, cap, want, line))
        if mismatches:
            print("FAIL: %d of %d cases differ between C++ and Python" % (mismatches, len(cases)))
            failures += 1
        else:
            print("ok: C++ and Python agree on %d cases (%d vectors + %d random/adversarial)"
                  % (len(cases), len(VECTORS), args.random))
    return 1 if failures else 0


def update():
    spec = open(SPEC_PATH, encoding="utf-8").read()
    start, end = spec.find(BEGIN_MARK), spec.find(END_MARK)
    if start < 0 or end < 0:
        raise SystemExit("markers not found in %s" % SPEC_PATH)
    spec = spec[:start] + markdown_table() + spec[end + len(END_MARK):]
    open(SPEC_PATH, "w", encoding="utf-8").write(spec)
    open(INC_PATH, "w", encoding="utf-8").write(inc_text())
    print("updated %s and %s" % (SPEC_PATH, INC_PATH))


def search_near_end():
    """Finds level-1 voxel centres whose base slot is clamped to the last window (for VECTORS)."""
    found_small = found_large = None
    for i in range(1, 90):
        for j in range(1, 90):
            for k in range(1, 90):
                h = hash32(pack((i, j, k), 1, 0))
                if found_small is None and h % SMALL_CAPACITY > SMALL_CAPACITY - BUCKET:
                    found_small = (i, j, k)
                if found_large is None and h % LARGE_CAPACITY > LARGE_CAPACITY - BUCKET:
                    found_large = (i, j, k)
        if found_small and found_large:
            break
    for g in (found_small, found_large):
        if g is not None:  # voxel centre at level 1 (voxel 0.04 for the defaults)
            print(vec_str(tuple(f32((c + 0.5) * 0.04) for c in g)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--update", action="store_true")
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--dump-exe")
    ap.add_argument("--random", type=int, default=20000)
    ap.add_argument("--search-near-end", action="store_true")
    args = ap.parse_args()
    if args.search_near_end:
        search_near_end()
        return 0
    if args.update:
        update()
        return 0
    if args.check:
        return check(args)
    print(markdown_table())
    return 0


if __name__ == "__main__":
    sys.exit(main())
