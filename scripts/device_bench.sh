#!/usr/bin/env bash
# The card's figures in one run on a machine with an NVIDIA card (docs/gpu.md, "Figures that
# wait for a card"): the reference cloth's sums in f32 and f64 on the card, then
# `hooke bench gpu` at 256², 1024² and 2048² (the CPU beside the card, one and many steps a
# submit, f32 and f64, and XPBD at a frame's step without contact and with particle pairs).
# Writes everything under $OUT (or ./out).
#
# It needs a release binary built where it will run (x86-64, the `gpu` feature: the default
# build, or a smaller headless one with `cargo build --release --no-default-features --features
# gpu`, then `strip`: the carried tree is at most 64 MiB) at $HOOKE (default .bin/hooke), and
# the Vulkan loader and libglvnd as .deb files in
# .gl/ when the machine has none (libvulkan1 libglvnd0 libegl1 libgl1 libglx0 libopengl0
# libgles2), which it unpacks.
set -uo pipefail
OUT="${OUT:-out}"
HOOKE="${HOOKE:-.bin/hooke}"
mkdir -p "$OUT"
if ! ldconfig -p | grep -q libvulkan && compgen -G ".gl/*.deb" >/dev/null; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [ -f "$icd" ]; then export VK_DRIVER_FILES="$icd"; fi
export NODEVICE_SELECT=1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv >"$OUT/card.csv" 2>&1
for p in f32 f64; do
  "$HOOKE" run --scene cloth32 --steps 1000 --device gpu --gpu-precision "$p" --json \
    --out "$OUT/cloth32_$p.csv" >"$OUT/cloth32_$p.json" 2>>"$OUT/log.txt"
done
# Σ(x + y) against shared/reference.md's 998.4039018283542 (symplectic Euler).
python3 - "$OUT" <<'PY' >>"$OUT/log.txt" 2>&1
import csv, sys
ref = 998.4039018283542
for p in ("f32", "f64"):
    rows = list(csv.reader(open(f"{sys.argv[1]}/cloth32_{p}.csv")))[1:]
    s = sum(float(r[1]) + float(r[2]) for r in rows)
    print(f"cloth32 {p}: sum {s!r}, relative {abs(s - ref) / ref:.2e}")
PY
"$HOOKE" bench gpu --widths "${WIDTHS:-256,1024,2048}" --budget "${BUDGET:-2e9}" --repeat 3 \
  --out "$OUT" 2>>"$OUT/log.txt"
tail -n 40 "$OUT/log.txt"
