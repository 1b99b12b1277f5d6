#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Batch work: several scenes in one bake (each with its own outputs and outcome; a failing scene
# does not stop the others) and bake settings in a config file that the command line overrides.
# Usage: batch_test.sh SHARCBAKE SCENES_DIR WORK_DIR
set -u
sharcbake=$1
scenes=$2
work=$3
. "$(dirname "$0")/../cli_support.sh"

furnace="$scenes/furnace_rho050/furnace_rho050.gltf"
cornell="$scenes/cornell_box/cornell_box.gltf"
small="--iterations 4 --resolution 160x90 --capacity 65536"
rm -rf "$work/batch" "$work/batch_q" "$work/stats" && mkdir -p "$work/broken"
printf '{ "asset": { "version": "2.0" }, "buffers": [ { "byteLength": 12, ' > "$work/broken/broken.gltf"  # JSON cut short

# Three scenes, the second broken: the other two are baked, the summary names each, exit 3.
expect 3 "a batch with a broken scene" "$sharcbake" bake "$furnace" "$work/broken/broken.gltf" "$cornell" \
    -o "$work/batch" --stats-json "$work/stats" $small
says "$work/out.txt" "Batch: 2 of 3 scenes baked" "the summary counts what was baked"
says "$work/out.txt" "ok  *.*furnace_rho050.gltf -> .*batch/furnace_rho050.sharc" "the summary names each output"
says "$work/out.txt" "exit 3 .*broken.gltf" "the summary names the failed scene and its exit code"
says "$work/err.txt" "broken.gltf" "the failed scene's error is printed"
for name in furnace_rho050 cornell_box; do
    [ -s "$work/batch/$name.sharc" ] || fail "the batch did not write $name.sharc"
    [ -s "$work/stats/$name.json" ] || fail "the batch did not write $name.json"
done
[ ! -e "$work/batch/broken.sharc" ] || fail "the broken scene left a cache"
# -q prints nothing but warnings and errors, a batch's summary included; the error names the scene.
expect 3 "a quiet batch with a broken scene" "$sharcbake" bake "$furnace" "$work/broken/broken.gltf" \
    -o "$work/batch_q" $small -q
[ -s "$work/out.txt" ] && fail "a -q batch printed on stdout: $(cat "$work/out.txt")"
says "$work/err.txt" "broken.gltf" "the quiet batch's error names the scene"
# Each scene's cache is the one a bake of that scene alone gives.
expect 0 "the cornell box alone" "$sharcbake" bake "$cornell" -o "$work/alone.sharc" $small -q
cmp -s "$work/alone.sharc" "$work/batch/cornell_box.sharc" || fail "a batch's cache differs from the same bake alone"

expect 1 "two scenes with one name" "$sharcbake" bake "$furnace" "$furnace" -o "$work/batch" $small
says "$work/err.txt" "same outputs" "the refusal says why"
expect 1 "--resume with several scenes" "$sharcbake" bake "$furnace" "$cornell" -o "$work/batch" --resume "$work/x.ckpt"
expect 2 "a batch into a file" sh -c "touch '$work/file' && '$sharcbake' bake '$furnace' '$cornell' -o '$work/file' $small"

# With several scenes -o names a folder: one named like a cache file is refused, not made.
expect 1 "several scenes into -o X.sharc" "$sharcbake" bake "$cornell" "$scenes/furnace_rho050/furnace_rho050.gltf" \
    -o "$work/batch.sharc" --iterations 1
says "$work/err.txt" "names a folder with several scenes" "the refusal says -o names a folder"
[ ! -e "$work/batch.sharc" ] || fail "a folder named batch.sharc was made"

# A config file: printed by --print-config, read by --config, overridden by the command line.
expect 0 "--print-config" "$sharcbake" bake "$cornell" -o "$work/from_config.sharc" $small --seed 3 --print-config
cp "$work/out.txt" "$work/bake.toml"
says "$work/bake.toml" "^\[bake\]" "the config has a [bake] section"
says "$work/bake.toml" "^seed=3" "the config holds the options given"
[ ! -e "$work/from_config.sharc" ] || fail "--print-config baked"
expect 0 "bake from the config" "$sharcbake" --config "$work/bake.toml" bake -q
expect 0 "the same bake from the command line" "$sharcbake" bake "$cornell" -o "$work/from_line.sharc" $small --seed 3 -q
cmp -s "$work/from_config.sharc" "$work/from_line.sharc" || fail "the config's bake differs from the command line's"
expect 0 "the command line overrides the config" "$sharcbake" --config "$work/bake.toml" bake -q --iterations 2 \
    -o "$work/override.sharc" --stats-json "$work/override.json"
python3 -c "import json,sys; j=json.load(open(sys.argv[1])); assert j['iterations'] == 2 and j['settings']['seed'] == 3, j['settings']" \
    "$work/override.json" && echo "ok: --iterations 2 overrides the file, its seed stays" || fail "override"
printf '[bake]\niteratoins = 5\n' > "$work/typo.toml"
expect 2 "a config file that is not there" "$sharcbake" --config "$work/missing.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "--config: .*missing.toml was not readable" "the missing config is named"
expect 1 "a config with a misspelt option" "$sharcbake" --config "$work/typo.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "iteratoins" "the error names the unknown key"
says "$work/err.txt" "typo.toml" "the error names the config file"
printf '[bake]\niterations = "many"\n' > "$work/bad_value.toml"
expect 1 "a config with a bad value" "$sharcbake" --config "$work/bad_value.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "bad_value.toml: .*iterations" "the error names the config file and the option"
# Values the bake checks itself, after the file is read, name the file too; so does a broken header.
printf '[bake]\nview-region = "glft"\n' > "$work/bad_region.toml"
expect 1 "a config with a bad view region" "$sharcbake" --config "$work/bad_region.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "bad_region.toml (\[bake\] view-region): --view-region" "the error names the config file and key"
printf '[bake\niterations = 2\n' > "$work/broken.toml"
expect 1 "a config with a broken section header" "$sharcbake" --config "$work/broken.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "broken.toml:1: a section header without its closing" "the broken header is named"
# A section header of 20,000 dotted parts (40 KB) took CLI11's reader 58 s and 12 GB: refused at once.
python3 -c "print('[' + '.'.join(['b'] * 20000) + ']')" > "$work/deep.toml"
expect 1 "a config nested 20,000 deep" timeout 20 "$sharcbake" --config "$work/deep.toml" bake "$cornell" -o "$work/x.sharc"
says "$work/err.txt" "deep.toml:1: a section or key nested 20000 levels deep (at most 16" "the nesting is refused naming the line"
# A list of a million values (2 MB) took it 21 s: refused at once. Commas in strings and comments
# do not count (a scene's path may hold them).
python3 -c "print('[bake]'); print('iterations = [' + ','.join(['1'] * 1000000) + ']')" > "$work/long_list.toml"
expect 1 "a config with a list of a million values" timeout 20 "$sharcbake" --config "$work/long_list.toml" bake "$cornell" \
    -o "$work/x.sharc"
says "$work/err.txt" "long_list.toml: lists of 1000000 values or more (at most 10000 in all" "the long list is refused"
python3 -c "print('# ' + ',' * 20000); print('[bake]'); print('output = \"a,b,c.sharc\"  # ' + ',' * 20000)" \
    > "$work/commas.toml"
expect 0 "commas in comments and strings" "$sharcbake" --config "$work/commas.toml" bake "$cornell" --iterations 1
[ -f "$work/a,b,c.sharc" ] || fail "the config's output with commas in its name was not written"

# Relative paths in a config file are relative to its folder (kept beside its scene), whatever the
# current folder; paths on the command line stay relative to the current folder.
mkdir -p "$work/level/out" "$work/elsewhere"
cp "$scenes/furnace_rho050/furnace_rho050.gltf" "$scenes/furnace_rho050/furnace_rho050.bin" "$work/level/"
printf '0 0.5 0 0 0.5 -1\n0.3 0.5 0 0 0.5 1\n' > "$work/level/path.txt"
cat > "$work/level/scene.toml" <<'EOF'
[bake]
scene = ["furnace_rho050.gltf"]
output = "out/level.sharc"
checkpoint = "out/level.ckpt"
stats-json = "out/level.json"
camera-path = "path.txt"
iterations = 4
resolution = "32x32"
capacity = 65536
EOF
expect 0 "a config with relative paths, from another folder" sh -c "cd '$work/elsewhere' && '$sharcbake' --config ../level/scene.toml bake -q"
for f in level.sharc level.ckpt level.json; do
    [ -s "$work/level/out/$f" ] || fail "the config's relative path out/$f was not taken from the config's folder"
done
says "$work/level/out/level.json" "path file path.txt (2 waypoints)" "the camera path is read from the config's folder"
# The cache records the paths as the config writes them, so the same config baked in another
# checkout gives the same bytes (the paths resolved against the file's folder made them differ).
cp -r "$work/level" "$work/level_copy" && rm -f "$work/level_copy/out/"*
expect 0 "the same config in another folder" "$sharcbake" --config "$work/level_copy/scene.toml" bake -q
cmp -s "$work/level/out/level.sharc" "$work/level_copy/out/level.sharc" ||
    fail "the same config baked in two folders gives different caches"
"$sharcbake" info "$work/level/out/level.sharc" > "$work/level_info.txt"
says "$work/level_info.txt" "scene: furnace_rho050.gltf$" "the cache records the scene's path as the config writes it"
expect 0 "the config's paths overridden on the command line" sh -c "cd '$work/elsewhere' && '$sharcbake' \
    --config ../level/scene.toml bake -q -o line.sharc --stats-json line.json --checkpoint line.ckpt"
[ -s "$work/elsewhere/line.sharc" ] && [ -s "$work/elsewhere/line.json" ] ||
    fail "paths given on the command line are not relative to the current folder"
cmp -s "$work/elsewhere/line.sharc" "$work/level/out/level.sharc" || fail "the same bake from another folder differs"
# --print-config writes absolute paths, so the printed file names the same files from anywhere.
expect 0 "--print-config with relative paths" sh -c "cd '$work/level' && '$sharcbake' bake furnace_rho050.gltf \
    -o out/printed.sharc --camera-path path.txt --iterations 4 --resolution 32x32 --capacity 65536 --print-config \
    > '$work/elsewhere/printed.toml'"
says "$work/elsewhere/printed.toml" "^scene=\"/.*level/furnace_rho050.gltf\"" "--print-config writes the scene's absolute path"
expect 0 "bake from the printed config in another folder" "$sharcbake" --config "$work/elsewhere/printed.toml" bake -q
[ -s "$work/level/out/printed.sharc" ] || fail "the printed config's bake did not write its absolute -o"

finish "batch and config"
