#!/usr/bin/env bash
# libdraco carries its own copy of tinygltf (another version) and of stb, and exports them. A
# program that took its tinygltf or stb symbols from there would parse glTF with one layout of
# tinygltf's classes and destroy them with another. For each program given: it defines none of
# those symbols itself (no copy was linked in from Draco's archive), and every one it uses binds
# to Debian's libtinygltf or libstb at run time, none to libdraco.
set -euo pipefail
status=0
for program in "$@"; do
    defined=$(nm -C "$program" | grep -cE ' T (tinygltf::|stbi_)' || true)  # inline ones (W) are ours
    if [ "$defined" != 0 ]; then
        echo "FAIL: $program defines $defined tinygltf/stb symbols (a copy linked in from libdraco.a?)"
        status=1
    fi
    bindings=$(LD_BIND_NOW=1 LD_DEBUG=bindings "$program" --help 2>&1 >/dev/null |
        grep "binding file $program " | grep -E "symbol \`(_ZN8tinygltf|_ZNK8tinygltf|stbi_)" || true)
    to_draco=$(grep -c "libdraco" <<<"$bindings" || true)
    to_debian=$(grep -cE "libtinygltf|libstb" <<<"$bindings" || true)
    if [ "$to_draco" != 0 ]; then
        echo "FAIL: $program binds $to_draco tinygltf/stb symbols to libdraco:"
        grep "libdraco" <<<"$bindings" | head -5
        status=1
    elif [ "$to_debian" = 0 ]; then
        echo "FAIL: $program binds no tinygltf/stb symbol at all (did the check see its bindings?)"
        status=1
    else
        echo "ok: $program binds its $to_debian tinygltf/stb symbols to Debian's libraries"
    fi
done
exit $status
