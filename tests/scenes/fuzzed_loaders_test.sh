#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The readers of files from elsewhere under libFuzzer + ASan + UBSan (ctest: scenes.fuzzed_loaders):
#   fuzz_gltf_loader.cpp  loadGltf (tinygltf's parse and everything the loader reads: accessors,
#                         sparse accessors, nodes, skins, materials, textures, lights, cameras,
#                         meshopt and Draco streams) for GLTF_FUZZ_SECONDS (default 45), seeded
#                         with the shipped scenes made self-contained (fuzz_seeds.py) and, where
#                         gltfpack is installed, their quantized and meshopt-compressed GLBs;
#   fuzz_linear_image.cpp readLinearImage (PFM, Radiance HDR flat and run-length, OpenEXR), the
#                         reader of other renderers' images, for IMAGE_FUZZ_SECONDS (default 20),
#                         seeded with images written here.
# A crash, a sanitizer report, a leak, an exception other than the reader's own, a broken promise
# of a loaded scene or image, or a run over 10 s fails the test, naming the reproducer.
# Without clang++ the test is skipped: exit 77 (ctest SKIP_RETURN_CODE).
# Usage: fuzzed_loaders_test.sh SOURCE_DIR WORK_DIR SHARCBAKE
set -euo pipefail
SRC=$(cd "$1" && pwd)
mkdir -p "$2"
WORK=$(cd "$2" && pwd)
SHARCBAKE=$3
GLTF_FUZZ_SECONDS=${GLTF_FUZZ_SECONDS:-45}
IMAGE_FUZZ_SECONDS=${IMAGE_FUZZ_SECONDS:-20}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

CXX_FUZZ=${CLANGXX:-$(command -v clang++ || true)}
if [ -z "$CXX_FUZZ" ]; then
    echo "SKIP: clang++ not found (apt-get install clang libclang-rt-14-dev)"
    exit 77
fi
FLAGS=(-std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
       -I"$SRC/scenes/include" -I"$SRC/scenes/src" -I"$SRC/viewer_export/include" -I"$SRC/viewer_export/src"
       -I"$SRC/cache_format/include" -isystem /usr/include/stb -I/usr/include/OpenEXR -I/usr/include/Imath
       -I/usr/include/draco)
EXR_LIBS=(-lOpenEXR-3_1 -lOpenEXRCore-3_1 -lIex-3_1 -lIlmThread-3_1 -lImath-3_1 -pthread)
IMAGE_SOURCES=("$SRC/viewer_export/src/image_exr.cpp" "$SRC/viewer_export/src/image_file.cpp"
               "$SRC"/cache_format/src/*.cpp)

. "$SRC/tests/fuzz_support.sh"

echo "== fuzz_gltf_loader"
dir="$WORK/fuzz_gltf_loader"
rm -rf "$dir" && mkdir -p "$dir/packed"
"$CXX_FUZZ" "${FLAGS[@]}" "$SRC/tests/scenes/fuzz_gltf_loader.cpp" "$SRC"/scenes/src/*.cpp "${IMAGE_SOURCES[@]}" \
    -o "$dir/fuzz_gltf_loader" -ltinygltf -lstb -lmeshoptimizer -lwebp -ldraco "${EXR_LIBS[@]}"
scenes=()
for gltf in "$SRC"/scenes/*/*.gltf; do scenes+=("$gltf"); done
if command -v gltfpack >/dev/null; then
    for gltf in "$SRC"/scenes/*/*.gltf; do
        name=$(basename "$gltf" .gltf)
        gltfpack -i "$gltf" -o "$dir/packed/$name.glb" >/dev/null && scenes+=("$dir/packed/$name.glb")
        gltfpack -c -i "$gltf" -o "$dir/packed/$name.meshopt.glb" >/dev/null && scenes+=("$dir/packed/$name.meshopt.glb")
    done
fi
python3 "$SRC/tests/scenes/fuzz_seeds.py" "$dir/corpus" "${scenes[@]}"
run_fuzzer "$dir/fuzz_gltf_loader" "$dir" "$GLTF_FUZZ_SECONDS" -dict="$SRC/tests/scenes/fuzz_gltf.dict" \
    -max_len=65536 -rss_limit_mb=3000

echo "== fuzz_linear_image"
dir="$WORK/fuzz_linear_image"
rm -rf "$dir" && mkdir -p "$dir/corpus"
"$CXX_FUZZ" "${FLAGS[@]}" "$SRC/tests/viewer_export/fuzz_linear_image.cpp" "$SRC/viewer_export/src/image_linear.cpp" \
    "${IMAGE_SOURCES[@]}" -o "$dir/fuzz_linear_image" "${EXR_LIBS[@]}"
"$SHARCBAKE" render "$SRC/scenes/cornell_box/cornell_box.gltf" --resolution 8x8 --spp 1 \
    -o "$dir/corpus/render.exr" >/dev/null
rm -f "$dir/corpus/render.png"
python3 - "$dir/corpus" <<'PY'
import math, os, random, struct, sys
out = sys.argv[1]
random.seed(1)
w, h = 16, 4
values = [random.random() * 4 for _ in range(w * h * 3)]
with open(os.path.join(out, "colour.pfm"), "wb") as f:  # little-endian colour
    f.write(b"PF\n%d %d\n-1.0\n" % (w, h) + struct.pack("<%df" % (w * h * 3), *values))
with open(os.path.join(out, "grey.pfm"), "wb") as f:  # big-endian grey
    f.write(b"Pf\n%d %d\n1.0\n" % (w, h) + struct.pack(">%df" % (w * h), *values[: w * h]))
def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return bytes(4)
    mantissa, exponent = math.frexp(m)
    s = mantissa * 256 / m
    return bytes([int(r * s), int(g * s), int(b * s), exponent + 128])
with open(os.path.join(out, "flat.hdr"), "wb") as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2.0\n\n-Y %d +X %d\n" % (h, w))
    f.write(b"".join(rgbe(*values[3 * i: 3 * i + 3]) for i in range(w * h)))
width = 32  # run-length scanlines: per component a run of 10, then 22 literals
with open(os.path.join(out, "rle.hdr"), "wb") as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, width))
    for y in range(h):
        pixels = [rgbe(random.random(), 0.5, 0.25) for _ in range(width)]
        f.write(bytes([2, 2, width >> 8, width & 255]))
        for c in range(4):
            f.write(bytes([128 + 10, pixels[0][c], width - 10]) + bytes(p[c] for p in pixels[10:]))
PY
run_fuzzer "$dir/fuzz_linear_image" "$dir" "$IMAGE_FUZZ_SECONDS" -max_len=8192 -rss_limit_mb=3000
echo "OK: the glTF loader fuzzed ${GLTF_FUZZ_SECONDS}s and the image reader ${IMAGE_FUZZ_SECONDS}s without a finding"
