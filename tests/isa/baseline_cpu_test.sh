#!/usr/bin/env bash
# One binary for every x86-64 CPU: runs the qdmr command under QEMU's user-mode emulation of a CPU without AVX
# (Nehalem: SSE4.2, no AVX/AVX2/FMA). It must render with the SSE4.2 kernel, give the same pixels as this
# machine's native SSE4.2 run, and refuse --isa avx2 and --isa avx512 with exit 2 and a message (never SIGILL).
# Skipped (exit 77) when qemu-x86_64 is not installed.
set -u
qdmr="$1"
scene="$2"
if ! command -v qemu-x86_64 >/dev/null 2>&1; then
  echo "skipped: qemu-x86_64 not found (Debian package qemu-user, installed by scripts/setup)"
  exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
common=(render "$scene" --width 96 --height 54 --threads 1)

out=$(qemu-x86_64 -cpu Nehalem "$qdmr" "${common[@]}" -o "$dir/emulated.exr" 2>&1)
code=$?
echo "$out"
if [ $code -ne 0 ]; then echo "FAIL: exit $code on an emulated CPU without AVX"; exit 1; fi
case "$out" in *sse4.2*) ;; *) echo "FAIL: the emulated run did not report the sse4.2 kernel"; exit 1;; esac

"$qdmr" "${common[@]}" --isa sse4.2 -o "$dir/native.exr" >/dev/null || { echo "FAIL: native sse4.2 run"; exit 1; }
# -fail 0: any difference at all fails (the same bits are the contract).
if ! idiff -q -fail 0 "$dir/native.exr" "$dir/emulated.exr" >/dev/null 2>&1; then
  echo "FAIL: the emulated pixels differ from the native SSE4.2 pixels"; exit 1
fi
for isa in avx2 avx512; do
  out=$(qemu-x86_64 -cpu Nehalem "$qdmr" "${common[@]}" --isa $isa -o "$dir/x.png" 2>&1)
  code=$?
  echo "$out"
  if [ $code -ne 2 ]; then echo "FAIL: --isa $isa on a CPU without it exited $code, expected 2"; exit 1; fi
  case "$out" in *"does not support $isa"*) ;; *) echo "FAIL: no message naming $isa"; exit 1;; esac
  [ ! -e "$dir/x.png" ] || { echo "FAIL: an output was written"; exit 1; }
done
echo "PASS"
