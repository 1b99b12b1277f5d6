#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Every JSON output, produced for real on the shipped scenes, against its schema in docs/schemas/:
# bake --stats-json and --report's convergence.json (probes; a furnace room's voxel and image
# errors), render --stats-json with and without --cache and with debug views, info --json,
# validate --json of a good, a corrupted and a missing file, compare --json. The schemas must be
# valid draft 2020-12 schemas, and broken outputs (a field missing, of the wrong type, or not in
# the layout) must fail, so that passing means something.
# Usage: json_schema_test.sh SHARCBAKE SCENES_DIR WORK_DIR SCHEMAS_DIR PYTHON
set -u
sharcbake=$1
scenes=$2
work=$3
schemas=$4
python=$5
. "$(dirname "$0")/../cli_support.sh"

cornell="$scenes/cornell_box/cornell_box.gltf"
furnace="$scenes/furnace_rho090/furnace_rho090.gltf"
small="--resolution 320x180 --capacity 65536"
image="--resolution 64x36 --spp 4 -q"

"$python" -c "import jsonschema" 2>/dev/null || { fail "$python has no jsonschema: install python3-jsonschema (make deps)"; finish cli.json_schemas; }

# Bakes: the Cornell box measures probes; the furnace room its voxels and a render through the
# cache against its known radiance (with the render's noise split off: --report-spp 2).
expect 0 "bake with --stats-json and --report" "$sharcbake" bake "$cornell" -o "$work/c.sharc" --iterations 16 $small \
    --report "$work/report" --report-probes 128 --report-probe-spp 32 --report-resolution 32 \
    --stats-json "$work/bake-stats.json" -q
cp "$work/err.txt" "$work/bake-stats-err.txt"  # its warnings, which the stats list
expect 0 "furnace bake with --report" "$sharcbake" bake "$furnace" -o "$work/f.sharc" --iterations 8 \
    --resolution 64x64 --capacity 65536 --report "$work/furnace_report" --report-probes 0 --report-resolution 16 \
    --report-spp 2 -q

# Renders: plain, through the cache, and debug views with and without the missing-voxel count.
expect 0 "render --stats-json" "$sharcbake" render "$cornell" -o "$work/plain.exr" $image \
    --stats-json "$work/render-stats.json"
expect 0 "render --cache --stats-json" "$sharcbake" render "$cornell" -o "$work/cached.exr" $image \
    --cache "$work/c.sharc" --stats-json "$work/render-stats-cache.json"
expect 0 "render --debug-view cache --stats-json" "$sharcbake" render "$cornell" -o "$work/debug.exr" $image \
    --cache "$work/c.sharc" --debug-view cache --stats-json "$work/render-stats-debug-cache.json"
expect 0 "render --debug-view bounces --stats-json" "$sharcbake" render "$cornell" -o "$work/bounces.exr" $image \
    --cache "$work/c.sharc" --debug-view bounces --stats-json "$work/render-stats-debug-bounces.json"
# The Cornell box's camera made orthographic: its stats give the view's half height, no yfov.
mkdir -p "$work/ortho"
cp "$(dirname "$cornell")/cornell_box.bin" "$work/ortho/"
"$python" - "$cornell" "$work/ortho/cornell_ortho.gltf" <<'PY' || fail "writing an orthographic Cornell box"
import json, sys
doc = json.load(open(sys.argv[1]))
doc["cameras"][0] = {"name": "iso", "type": "orthographic",
                     "orthographic": {"xmag": 0.6, "ymag": 0.6, "znear": 0.01, "zfar": 100}}
json.dump(doc, open(sys.argv[2], "w"))
PY
expect 0 "render from an orthographic camera --stats-json" "$sharcbake" render "$work/ortho/cornell_ortho.gltf" \
    -o "$work/ortho.exr" --resolution 64 --spp 4 -q --stats-json "$work/render-stats-ortho.json"

# A flat of lamp-lit rooms on a ground 2 km wide: light selection adds a detail grid.
"$python" "$(dirname "$0")/../bench/light_selection_scenes.py" "$work" || fail "writing the light-selection scenes"
expect 0 "render with a light-selection detail grid --stats-json" "$sharcbake" render "$work/flat_on_ground.gltf" \
    -o "$work/detail.exr" --resolution 16 --spp 1 -q --stats-json "$work/render-stats-detail.json"

# info, validate (a good file, one with a byte flipped in its voxels, a missing one), compare.
expect 0 "info --json" sh -c "'$sharcbake' info '$work/c.sharc' --json > '$work/info.json'"
expect 0 "validate --json, valid" sh -c "'$sharcbake' validate '$work/c.sharc' --json > '$work/validate-ok.json'"
"$python" - "$work/c.sharc" "$work/corrupt.sharc" <<'PY' || fail "corrupting a copy of the cache"
import sys
data = bytearray(open(sys.argv[1], "rb").read())
data[len(data) // 2] ^= 0xFF
open(sys.argv[2], "wb").write(data)
PY
expect 3 "validate --json, corrupted" sh -c "'$sharcbake' validate '$work/corrupt.sharc' --json > '$work/validate-corrupt.json'"
expect 2 "validate --json, missing" sh -c "'$sharcbake' validate '$work/none.sharc' --json > '$work/validate-missing.json'"
expect 0 "compare --json" sh -c "'$sharcbake' compare '$work/cached.exr' '$work/plain.exr' --json > '$work/compare.json'"

"$python" - "$schemas" "$work" <<'PY' || fail "JSON outputs against docs/schemas/"
import copy, glob, json, os, sys
from jsonschema import Draft202012Validator

schemas_dir, work = sys.argv[1], sys.argv[2]
failures = []

def check(condition, what):
    print(("ok: " if condition else "FAIL: ") + what)
    if not condition:
        failures.append(what)

# The schemas themselves, and the outputs each one describes.
outputs = {
    "bake-stats": ["bake-stats.json"],
    "render-stats": ["render-stats.json", "render-stats-cache.json", "render-stats-debug-cache.json",
                     "render-stats-debug-bounces.json", "render-stats-ortho.json", "render-stats-detail.json"],
    "info": ["info.json"],
    "validate": ["validate-ok.json", "validate-corrupt.json", "validate-missing.json"],
    "compare": ["compare.json"],
    "convergence": ["report/convergence.json", "furnace_report/convergence.json"],
}
names = sorted(os.path.basename(p)[:-len(".schema.json")] for p in glob.glob(schemas_dir + "/*.schema.json"))
check(names == sorted(outputs), "one schema per output: %s" % names)
validators, documents = {}, {}
for name in outputs:
    schema = json.load(open("%s/%s.schema.json" % (schemas_dir, name)))
    Draft202012Validator.check_schema(schema)
    check(schema["title"] == "sharcbake.%s/1" % name and schema["properties"]["schema"] == {
        "const": "sharcbake.%s/1" % name, "description": schema["properties"]["schema"]["description"]},
        "%s.schema.json is a valid draft 2020-12 schema for sharcbake.%s/1" % (name, name))
    validators[name] = Draft202012Validator(schema)  # no format checker: formats are not checked
    for file in outputs[name]:
        documents[file] = json.load(open(work + "/" + file))

def errors(name, document):
    return ["%s: %s" % ("/".join(map(str, e.absolute_path)) or "(top)", e.message)
            for e in validators[name].iter_errors(document)]

for name, files in outputs.items():
    for file in files:
        problems = errors(name, documents[file])
        check(not problems, "%s matches %s.schema.json%s" % (file, name, "".join("\n  " + p for p in problems)))

# The outputs reach the optional parts of the schemas, so those are tested too.
check("cache_hits" in documents["render-stats-cache.json"] and "cache_hits" not in documents["render-stats.json"],
      "render stats: cache_* fields only with --cache")
ortho = documents["render-stats-ortho.json"]["camera"]
check(ortho["yfov"] is None and ortho["orthographic_half_height"] == 0.6
      and "orthographic_half_height" not in documents["render-stats.json"]["camera"],
      "render stats: an orthographic camera's half height, no yfov; none for a perspective camera")
check("debug_missing" in documents["render-stats-debug-cache.json"]
      and "debug_missing" not in documents["render-stats-debug-bounces.json"], "render stats: debug_missing only with --debug-view cache")
detail = documents["render-stats-detail.json"]["light_selection"]["detail"]
check(detail is not None and detail["cell_size"] < 1.0 and documents["render-stats.json"]["light_selection"]["detail"] is None,
      "render stats: a light-selection detail grid over the flat on a 2 km ground, none in the Cornell box")
# The stats list the warnings the command printed (the hit-rate, coverage and "will be black"
# warnings were in the log only); the stability section's are under stability.warnings.
printed = [line[len("warning: "):].rstrip("\n") for line in open(work + "/bake-stats-err.txt") if line.startswith("warning: ")]
listed = documents["bake-stats.json"]["warnings"]
stability = documents["bake-stats.json"]["stability"]["warnings"]
check(listed and all(w in printed for w in listed) and all(w in listed or w in stability for w in printed),
      "bake stats: warnings lists what the bake printed (%d of %d lines)" % (len(listed), len(printed)))
check(any("light leak" in w for w in listed), "bake stats: the Cornell box's light-leak warning is listed")
check(any("probes" in row for row in documents["report/convergence.json"]["checkpoints"]), "convergence.json rows with probes")
furnace = documents["furnace_report/convergence.json"]
check(any("voxel" in row for row in furnace["checkpoints"]) and
      any("cache_relative_mse" in row.get("image", {}) for row in furnace["checkpoints"]) and
      furnace["plain_path_tracing"], "furnace convergence.json rows with voxel and image errors, plain path tracing")
check(not documents["validate-corrupt.json"]["valid"] and documents["validate-corrupt.json"]["rule"],
      "validate --json names the failed rule of a corrupted file")

# Broken outputs fail: every top-level field removed, or given a value of another type, and a
# few deeper breaks of the layout.
def other_type(value):
    if isinstance(value, str): return 12345
    if isinstance(value, (dict, list)): return "text"
    return {"not": "this"}  # numbers, booleans, null

for name, files in outputs.items():
    document = documents[files[0]]
    for key in document:
        broken = dict(document)
        del broken[key]
        if key in validators[name].schema["required"]:
            check(not validators[name].is_valid(broken), "%s without \"%s\" fails" % (files[0], key))
        broken[key] = other_type(document[key])
        check(not validators[name].is_valid(broken), "%s with \"%s\" of another type fails" % (files[0], key))
    broken = dict(document, unknown_field=1)
    check(not validators[name].is_valid(broken), "%s with a field not in the layout fails" % files[0])

def breaks(name, file, what, change):
    broken = copy.deepcopy(documents[file])
    change(broken)
    check(not validators[name].is_valid(broken), "%s: %s fails" % (file, what))

breaks("bake-stats", "bake-stats.json", "seconds.total as a string", lambda d: d["seconds"].update(total="1.5"))
breaks("bake-stats", "bake-stats.json", "a view without \"rate\"", lambda d: d["predicted_hit_rate"]["views"][0].pop("rate"))
breaks("bake-stats", "bake-stats.json", "a stability count that is not an integer", lambda d: d["stability"].update(deposits=1.5))
breaks("bake-stats", "bake-stats.json", "a settings value that is a list", lambda d: d["settings"].update(seed=[1]))
breaks("bake-stats", "bake-stats.json", "another schema version", lambda d: d.update(schema="sharcbake.bake-stats/2"))
breaks("render-stats", "render-stats-cache.json", "--cache without cache_hits", lambda d: d.pop("cache_hits"))
breaks("render-stats", "render-stats.json", "cache_hits without --cache", lambda d: d.update(cache_hits=1))
breaks("render-stats", "render-stats-debug-cache.json", "--debug-view cache without debug_missing", lambda d: d.pop("debug_missing"))
breaks("render-stats", "render-stats.json", "a camera position of two components", lambda d: d["camera"]["position"].pop())
breaks("info", "info.json", "a section's crc32 below 0", lambda d: d["sections"][0].update(crc32=-1))
breaks("info", "info.json", "valid false", lambda d: d.update(valid=False))
breaks("validate", "validate-corrupt.json", "valid true with a failed rule", lambda d: d.update(valid=True))
breaks("validate", "validate-ok.json", "status \"ok\" of an invalid file", lambda d: d.update(valid=False))
breaks("compare", "compare.json", "relative_mse as \"NaN\"", lambda d: d.update(relative_mse="NaN"))
breaks("convergence", "report/convergence.json", "a probe measure without \"leaks\"",
       lambda d: next(r for r in d["checkpoints"] if "probes" in r)["probes"]["view"].pop("leaks"))
breaks("convergence", "furnace_report/convergence.json", "an image measure with a field not in the layout",
       lambda d: next(r for r in d["checkpoints"] if "image" in r)["image"].update(extra=1))
breaks("convergence", "furnace_report/convergence.json", "half of the image's noise split",
       lambda d: next(r for r in d["checkpoints"] if "image" in r)["image"].pop("cache_relative_mse"))
breaks("convergence", "furnace_report/convergence.json", "a plain path tracing image with the noise split",
       lambda d: d["plain_path_tracing"][0]["image"].update(cache_relative_mse=0.0))
sys.exit(1 if failures else 0)
PY

finish cli.json_schemas
