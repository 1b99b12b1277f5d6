#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# `bake --report` and `--target-error`: the tables have the documented columns, error falls
# during a Cornell box bake, the rho = 0.9 furnace ends under 2% against its analytic radiance,
# and --target-error stops early with the target met.
# Usage: report_test.sh SHARCBAKE SCENES_DIR WORK_DIR PYTHON
set -u
sharcbake=$1
scenes=$2
work=$3
python=$4
. "$(dirname "$0")/../cli_support.sh"

# Checks a report folder with Python (stdlib only): columns, JSON, PNG, and a condition on the
# rows, given as a Python expression over `rows` (convergence.csv as dicts of floats or None),
# `plain` (plain_path_tracing.csv) and `report` (convergence.json).
check_report() {  # check_report DIR DESCRIPTION EXPRESSION
    "$python" - "$1" "$3" <<'EOF' || fail "$2"
import csv, json, sys
folder, condition = sys.argv[1], sys.argv[2]
columns = ["iteration", "bake_seconds", "render_seconds", "total_seconds", "rays", "live_voxels",
           "voxel_mean_relative_error", "voxel_rms_relative_error", "voxel_max_relative_error",
           "voxel_within_1_percent", "image_relative_mse", "image_mean_relative_error", "image_relative_bias",
           "image_render_noise_relative_mse", "image_cache_relative_mse", "image_cache_relative_mse_standard_error",
           "image_tile_mean_relative_error", "image_masked_mean_relative_error", "image_masked_relative_mse",
           "probe_pairs", "probe_not_live", "probe_mean_relative_error", "probe_rms_error", "probe_relative_mse",
           "probe_relative_mse_ci95", "probe_voxel_noise", "probe_bias_squared", "probe_relative_bias",
           "probe_relative_bias_ci95", "probe_reference_noise", "probe_leaks"]
plain_columns = ["samples_per_pixel", "seconds", "rays", "image_relative_mse", "image_mean_relative_error",
                 "image_relative_bias", "image_tile_mean_relative_error", "image_masked_mean_relative_error",
                 "image_masked_relative_mse"]
def read(name, expected):
    with open(folder + "/" + name) as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == expected, "%s columns %s" % (name, reader.fieldnames)
        return [{k: (float(v) if v != "" else None) for k, v in row.items()} for row in reader]
rows = read("convergence.csv", columns)
plain = read("plain_path_tracing.csv", plain_columns)
report = json.load(open(folder + "/convergence.json"))
assert len(report["checkpoints"]) == len(rows) and len(report["plain_path_tracing"]) == len(plain)
assert open(folder + "/convergence.png", "rb").read(8) == b"\x89PNG\r\n\x1a\n", "convergence.png is not a PNG"
# Probe rows: the RMS is the root of the mean square, which splits into voxel noise and bias.
for r in rows:
    if r["probe_rms_error"] is None: continue
    assert r["probe_pairs"] > 0 and r["probe_relative_mse_ci95"] >= 0 and r["probe_reference_noise"] >= 0, r
    assert abs(r["probe_rms_error"] - max(0, r["probe_relative_mse"]) ** 0.5) <= 1e-4 * r["probe_rms_error"] + 1e-6, r
    assert abs(r["probe_relative_mse"] - r["probe_voxel_noise"] - r["probe_bias_squared"]) <= 1e-4 + 1e-3 * r["probe_relative_mse"], r
probe_rows = [r for r in rows if r["probe_rms_error"] is not None]
iterations = [r["iteration"] for r in rows]
assert iterations == sorted(set(iterations)) and iterations[0] == 1, iterations
assert all(r["bake_seconds"] >= 0 and r["rays"] > 0 for r in rows) and rows[-1]["live_voxels"] > 0
# Where an image is measured, its relative MSE splits into the render's noise and the rest.
for r in rows:
    if r["image_relative_mse"] is None: continue
    noise, rest = r["image_render_noise_relative_mse"], r["image_cache_relative_mse"]
    assert noise > 0 and r["image_cache_relative_mse_standard_error"] >= 0, r
    assert abs(r["image_relative_mse"] - noise - rest) <= 1e-4 * r["image_relative_mse"] + 1e-9, r
ok = eval("(" + condition + ")")
print("rows:", [(int(r["iteration"]), r["voxel_mean_relative_error"], r["image_mean_relative_error"]) for r in rows])
print("plain:", [(int(p["samples_per_pixel"]), p["seconds"], p["image_mean_relative_error"]) for p in plain])
sys.exit(0 if ok else 1)
EOF
}

furnace="$scenes/furnace_rho090/furnace_rho090.gltf"
cornell="$scenes/cornell_box/cornell_box.gltf"
small="--resolution 160x160 --voxel-budget 1024 --capacity 262144 --report-resolution 48"

# Usage errors come before any work.
expect 1 "--report without anything to measure against" \
    "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 2 --report "$work/none" --report-probes 0
grep -q "reference" "$work/err.txt" || fail "the message does not say to give --reference"
expect 1 "--target-error without anything to measure against" \
    "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 2 --target-error 0.1 --report-probes 0
# The report's options without a report: --reference alone baked without a word of measurement.
expect 1 "--reference without --report" \
    "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 2 --reference "$work/none.exr"
says "$work/err.txt" "--reference shapes the error report, which only --report DIR" "the refusal says what it needs"
[ ! -e "$work/c.sharc" ] || fail "a refused bake wrote its cache"
expect 2 "missing --reference" \
    "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 2 --report "$work/r" --reference "$work/none.exr"
# A refusal leaves no report folder behind, also one that comes after the scene is loaded.
[ ! -e "$work/r" ] || fail "a refused bake left its --report folder behind (missing --reference)"
expect 1 "an unknown --report-camera" \
    "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 2 --report "$work/r" --report-camera nope
[ ! -e "$work/r" ] || fail "a refused bake left its --report folder behind (unknown --report-camera)"
expect 1 "--report-resolution different from the reference" sh -c \
    "'$sharcbake' render '$cornell' -o '$work/tiny.exr' --resolution 8x8 --spp 1 -q &&
     '$sharcbake' bake '$cornell' -o '$work/c.sharc' --iterations 2 --report '$work/r' --reference '$work/tiny.exr' --report-resolution 16x16"

# The report's files against the other outputs, before any work: --stats-json inside the report
# folder under one of its names replaced the report's file (exit 0); --report equal to -o made a
# folder there before refusing (exit 2, the folder left behind); an existing file was called a
# folder that "does not exist". A refusal leaves no folder it made.
expect 1 "--stats-json over the report's convergence.json" \
    "$sharcbake" bake "$furnace" -o "$work/f.sharc" --iterations 2 --report "$work/clash" \
    --stats-json "$work/clash/convergence.json"
says "$work/err.txt" "the report would overwrite .*clash/convergence.json" "the clash names the file"
[ -e "$work/clash" ] && fail "the refused bake left its report folder behind"
expect 1 "--report equal to -o" "$sharcbake" bake "$furnace" -o "$work/same.sharc" --iterations 2 --report "$work/same.sharc"
says "$work/err.txt" "the report folder would take the cache's path" "the clash with the cache is named"
[ -e "$work/same.sharc" ] && fail "the refused bake made a folder at the cache's path"
printf 'notes\n' > "$work/notes.txt"
expect 2 "--report naming a file" "$sharcbake" bake "$furnace" -o "$work/f.sharc" --iterations 2 --report "$work/notes.txt"
says "$work/err.txt" "notes.txt: --report names a file, not a folder" "the file is called a file"
[ "$(cat "$work/notes.txt")" = notes ] || fail "the file named by --report changed"

# Furnace, rho = 0.9: every surface has radiance 10; the voxels end under 2% mean relative error.
expect 0 "furnace bake with --report" \
    "$sharcbake" bake "$furnace" -o "$work/furnace.sharc" --iterations 1024 $small --report "$work/furnace"
check_report "$work/furnace" "furnace: voxel error under 2% at the end, falling, and a plain path tracing curve" \
    'rows[-1]["voxel_mean_relative_error"] < 0.02 and rows[-1]["iteration"] == 1024 and
     rows[0]["voxel_mean_relative_error"] > 4 * rows[-1]["voxel_mean_relative_error"] and
     rows[-1]["image_mean_relative_error"] < 0.03 and len(plain) >= 2 and
     plain[-1]["seconds"] >= rows[-1]["total_seconds"] and report["reference"] == "known radiance"'

# --target-error stops at the first checkpoint that meets it, and that checkpoint meets it.
expect 0 "furnace bake with --target-error" \
    "$sharcbake" bake "$furnace" -o "$work/target.sharc" --iterations 100000 $small --target-error 0.05 \
    --report "$work/target" --stats-json "$work/target.json"
check_report "$work/target" "--target-error: stopped early with the target met" \
    'rows[-1]["voxel_mean_relative_error"] <= 0.05 and rows[-2]["voxel_mean_relative_error"] > 0.05 and
     rows[-1]["iteration"] < 100000 and report["target_error"] == 0.05'
grep -q '"stop_reason": "target error"' "$work/target.json" || fail "stats JSON does not say the target stopped the bake"
"$sharcbake" info "$work/target.sharc" > "$work/info.txt" 2>&1 && grep -q "target error" "$work/info.txt" ||
    fail "the cache's metadata does not record the stop reason"

# Level bias 0 keeps this room on level 1, whose voxels keep the light and the ceiling apart (see
# cli_test.sh; docs/baking.md, "Light leaks").
# Cornell box against a reference render: the image error falls between the first and the last
# checkpoint, and so does the render's own noise (paths end on the cache). Not the relative MSE:
# a single firefly of this small reference dominates it (see the rest's standard error).
expect 0 "reference render" "$sharcbake" render "$cornell" -o "$work/reference.exr" --resolution 48 --spp 512 -q
expect 0 "Cornell box bake with --report --reference" \
    "$sharcbake" bake "$cornell" -o "$work/cornell.sharc" --iterations 32 --resolution 320x320 --level-bias 0 \
    --reference "$work/reference.exr" --report "$work/cornell"
check_report "$work/cornell" "Cornell box: image error falls" \
    'rows[-1]["image_mean_relative_error"] < 0.9 * rows[0]["image_mean_relative_error"] and
     rows[-1]["image_render_noise_relative_mse"] < 0.75 * rows[0]["image_render_noise_relative_mse"] and
     rows[-1]["voxel_mean_relative_error"] is None and len(plain) >= 2'
grep -q "plain path tracing" "$work/out.txt" || fail "the summary does not compare with plain path tracing"

# Any scene, no reference: the probes measure the cache itself. With the defaults the Cornell
# box's error at the probes falls with bake time and flattens at the bias floor the report states:
# the last checkpoints lie within a factor 1.5 of one another and the end within 2x the floor.
expect 0 "Cornell box bake with --report and no reference" \
    "$sharcbake" bake "$cornell" -o "$work/probes.sharc" --report "$work/probes"
check_report "$work/probes" "Cornell box: probe error falls and flattens at the stated floor" \
    'len(probe_rows) >= 10 and probe_rows[0]["probe_rms_error"] > 2 * probe_rows[-1]["probe_rms_error"] and
     max(r["probe_rms_error"] for r in probe_rows[-3:]) < 1.5 * min(r["probe_rms_error"] for r in probe_rows[-3:]) and
     report["probe_floor"]["bias_floor"] > 0 and probe_rows[-1]["probe_rms_error"] < 2 * report["probe_floor"]["bias_floor"] and
     probe_rows[-1]["probe_pairs"] >= 1000 and report["reference"] == "probe reference" and len(plain) == 0'
grep -q "bias floor (fitted over" "$work/out.txt" || fail "the summary does not state the bias floor"

# --target-error on a scene without a known radiance stops on the probes' mean relative error.
expect 0 "Cornell box bake with --target-error on the probes" \
    "$sharcbake" bake "$cornell" -o "$work/probe_target.sharc" --iterations 100000 --target-error 0.3 \
    --report-probes 512 --report "$work/probe_target"
check_report "$work/probe_target" "--target-error on the probes: stopped early with the target met" \
    'rows[-1]["iteration"] < 100000 and report["target_error"] == 0.3 and
     report["checkpoints"][-1]["probes"]["view"]["mean_relative_error"] <= 0.3 + 0.05'

finish "report"
