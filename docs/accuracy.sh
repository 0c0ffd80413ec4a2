#!/bin/bash
# Re-measures docs/accuracy.md: path-traced references, the bias table, the knob table and the
# sweeps. Takes about 45 minutes on 2 cores, the references most of it (OUT_DIR keeps them).
# Usage: docs/accuracy.sh OUT_DIR [OLD_BINARY]   (OLD_BINARY: a build of ba22335 for "before")
set -euo pipefail
OUT=${1:?usage: docs/accuracy.sh OUT_DIR [OLD_BINARY]}
OLD=${2:-}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --manifest-path "$ROOT/Cargo.toml"
[ -f "$ROOT/scenes/gallery/gallery.obj" ] || (cd "$ROOT" && cargo run --release -p meshlight-gallery)
M="$ROOT/target/release/meshlight"
mkdir -p "$OUT" && cd "$OUT"

# Scene variants: `room` and `cornell` at 256² (room95s: 128²), their whites at Kd 0.85 / 0.95;
# the gallery at 192×128.
variant() { # name source-dir kd width height
  mkdir -p "$1" && cp "$ROOT/scenes/$2"/*.{obj,mtl,toml} "$1/"
  sed -i "s/^width = .*/width = $4/; s/^height = .*/height = $5/" "$1/scene.toml"
  [ "$3" = "-" ] || sed -i "/newmtl white/,/^Kd/ s/^Kd .*/Kd $3 $3 $3/" "$1"/*.mtl
}
variant room room - 256 256
variant room85 room 0.85 256 256
variant room95 room 0.95 256 256
variant room95s room 0.95 128 128
variant cornell cornell - 256 256
variant cornell95 cornell 0.95 256 256
mkdir -p gallery && cp "$ROOT/scenes/gallery/scene.toml" gallery/
ln -sf "$ROOT/scenes/gallery/gallery.obj" "$ROOT/scenes/gallery/gallery.mtl" gallery/
sed -i "s/^width = .*/width = 192/; s/^height = .*/height = 128/" gallery/scene.toml

# References (kept when OUT_DIR already holds them: they do not depend on the solver).
ref() { [ -f "ref_$1.exr" ] && return; "$M" render "$1/scene.toml" --method pathtrace --spp "$2" -o "ref_$1.exr" > "ref_$1.log" 2>/dev/null; }
ref room 8192; ref room85 2048; ref room95 4096; ref room95s 40000
ref cornell 1024; ref cornell95 1024; ref gallery 16384

# Bias before (OLD), now (hierarchy, the default) and flat.
: > bias.txt
for s in room95s room room85 room95 cornell cornell95; do
  for v in old new flat; do
    case $v in old) [ -n "$OLD" ] || continue; B=$OLD; X="";; new) B=$M; X="";; flat) B=$M; X="--cluster-threshold 0";; esac
    $B render "$s/scene.toml" $X -o "${v}_$s.exr" > "${v}_$s.log" 2>/dev/null
    echo "== $s $v: $(grep -E '^total' "${v}_$s.log")" >> bias.txt
    "$M" compare "${v}_$s.exr" "ref_$s.exr" >> bias.txt
  done
done

# Each knob alone from the defaults, on room.
for k in "epsilon=0.4,0.18" "zeta=0.1,0.4" "rounds=0,1" "alpha=0,2,32" "light-samples=4,64" \
         "tolerance=1e-2,1e-4" "seed=1" "cluster-threshold=0,0.01,0.2,1" "direct-rays=0,4,64" \
         "supersample=1,8"; do
  "$M" sweep room/scene.toml --reference ref_room.exr --vary "$k" --no-pathtrace --out "knob_${k%%=*}" > "knob_${k%%=*}.txt" 2>/dev/null
done

# Error against time: meshless (with the path tracer's curve), patches, gallery.
"$M" sweep room/scene.toml --reference ref_room.exr --vary epsilon=0.5,0.35,0.25,0.18,0.125 --vary rounds=0,2 \
  --out sw_room --pathtrace-seconds 60 --max-spp 4096 > sw_room.txt 2>/dev/null
"$M" sweep room/scene.toml --reference ref_room.exr --method patches --vary patch-size=0.5,0.35,0.25,0.18,0.125 \
  --no-pathtrace --out sw_room_patches > sw_room_patches.txt 2>/dev/null
"$M" sweep gallery/scene.toml --reference ref_gallery.exr --vary epsilon=0.6,0.45,0.3,0.2,0.15 --vary rounds=0,2 \
  --block 4 --out sw_gallery --pathtrace-seconds 100 --max-spp 4096 > sw_gallery.txt 2>/dev/null
echo "done: $OUT"
