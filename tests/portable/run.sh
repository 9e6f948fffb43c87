#!/usr/bin/env bash
# The default (portable) build runs on a baseline x86-64 CPU: sdfc under qemu-user's qemu64
# CPU less SSE3, CMPXCHG16B and LAHF (x86-64-v1: SSE2, no AVX; qemu stops an instruction the
# CPU lacks with an illegal instruction, so one outside the run-time dispatch fails the test)
# chooses the baseline kernels and draws every example, a 2D model and a mesh bit for bit as
# this machine's best kernels do (tests/runtime/test_isa.cpp: the copies compute the same
# floats). Exit 77 (ctest: skipped) without qemu-x86_64 (apt-get install qemu-user) or on a
# CPU that is not x86-64.
#   run.sh SOURCE_DIR SDFC_BINARY
set -uo pipefail
src=$1
sdfc=$2
[[ $(uname -m) == x86_64 ]] || { echo "SKIPPED: not an x86-64 machine"; exit 77; }
command -v qemu-x86_64 >/dev/null || { echo "SKIPPED: no qemu-x86_64 (apt-get install qemu-user)"; exit 77; }
ulimit -c 0  # (a failing run leaves no core file)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
on_baseline_cpu() { qemu-x86_64 -cpu qemu64,-sse3,-cx16,-lahf-lm "$sdfc" "$@"; }
fail=0
same() {  # same NAME EXT ARGS...: `sdfc ARGS -o FILE.EXT` here and on the baseline CPU, byte for byte
    local name=$1 here=$tmp/$1.here.$2 there=$tmp/$1.baseline.$2
    shift 2
    "$sdfc" "$@" -o "$here" --quiet || { echo "FAILED: $name (here)"; fail=1; return; }
    on_baseline_cpu "$@" -o "$there" --quiet || { echo "FAILED: $name on the baseline CPU (exit $?)"; fail=1; return; }
    if cmp -s "$here" "$there"; then echo "ok: $name"; else echo "FAILED: $name differs on the baseline CPU"; fail=1; fi
}

isa=$(on_baseline_cpu bench "$src/examples/lattice.sdf" --width 32 --height 18 --repeat 1 --warmup 0 | sed -n 's/.*isa=\([a-z0-9-]*\).*/\1/p')
if [[ $isa != x86-64 ]]; then echo "FAILED: on the baseline CPU sdfc chose the kernels '$isa', not x86-64"; fail=1; fi

for f in "$src"/examples/*.sdf; do
    same "$(basename "$f")" png render "$f" --width 128 --height 72 --threads 2
done
vm=$src/../shared/bench/vm/prospero.vm
[[ -f $vm ]] && same prospero.vm png render "$vm" --width 256 --height 256
same "csg-tori.sdf mesh" stl mesh "$src/examples/csg-tori.sdf" --resolution 48
exit $fail
