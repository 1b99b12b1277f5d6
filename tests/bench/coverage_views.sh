#!/bin/sh
# Hit rate of SHaRC's exact lookups from cameras on the line from the target through the outdoor
# scene's glTF camera, at 0.25x to 8x its distance, for a default bake and one with the SDK's rule, in
# metres and millimetres (BENCHMARKS.md, "Level coverage"). Run from the repository root after make build.
S=${SHARCBAKE:-build/bin/sharcbake}
out=${OUT:-out/coverage_views}
mkdir -p $out/mm; cp scenes/outdoor/outdoor.bin $out/mm/
python3 - scenes/outdoor/outdoor.gltf 1000 $out/mm/outdoor.gltf <<'PY'
import json, sys
g = json.load(open(sys.argv[1])); k = float(sys.argv[2])
g["nodes"].append({"name": "units", "scale": [k, k, k], "children": g["scenes"][0]["nodes"]})
g["scenes"][0]["nodes"] = [len(g["nodes"]) - 1]
json.dump(g, open(sys.argv[3], "w"))
PY
for units in m mm; do
  g=scenes/outdoor/outdoor.gltf; k=1
  [ $units = mm ] && g=$out/mm/outdoor.gltf && k=1000
  for mode in coverage sdk; do
    args=""; [ $mode = sdk ] && args="--view-region bake-camera --level-bias 0"
    $S bake $g -o $out/o.$units.$mode.sharc -q $args --stats-json $out/o.$units.$mode.json 2>/dev/null
    line="outdoor($units) $mode voxels=$(grep -o '"live_voxels": [0-9]*' $out/o.$units.$mode.json | cut -d' ' -f2):"
    for f in 0.25 0.5 1 2 4 8; do
      eye=$(python3 -c "t=(1.5,0.5,-1.5);c=(-3,6.5,14);print(','.join('%g'%($k*(t[i]+$f*(c[i]-t[i]))) for i in range(3)))")
      tgt=$(python3 -c "print(','.join('%g'%($k*v) for v in (1.5,0.5,-1.5)))")
      $S render $g -o $out/v.exr --look-at $eye,$tgt --fov 45 --resolution 96 --spp 4 --cache $out/o.$units.$mode.sharc --no-png -q --stats-json $out/v.json 2>/dev/null
      line="$line $f:$(python3 -c "import json;s=json.load(open('$out/v.json'));print('%.3f'%(s['cache_hits']/max(1,s['cache_hits']+s['cache_misses'])))")"
    done
    echo "$line"
  done
done
