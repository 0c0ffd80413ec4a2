#!/bin/bash
# Re-measures docs/accuracy.md: path-traced references, the defaults scene by scene (and the
# high-albedo bias over ten seeds), the knob table and the sweeps. About 45 minutes on 2
# cores, the references most of it (OUT_DIR keeps them).
# Usage: docs/accuracy.sh OUT_DIR
set -euo pipefail
OUT=${1:?usage: docs/accuracy.sh OUT_DIR}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --manifest-path "$ROOT/Cargo.toml"
[ -f "$ROOT/scenes/gallery/gallery.obj" ] || (cd "$ROOT" && cargo run --release -p meshlight-gallery)
M="$ROOT/target/release/meshlight"
mkdir -p "$OUT" && cd "$OUT"

# Scene variants: `room` at 256², `room` and `cornell` at 128² with their whites at their own Kd
# or 0.95; the gallery at 192×128.
variant() { # name source-dir kd width height
  mkdir -p "$1" && cp "$ROOT/scenes/$2"/*.{obj,mtl,toml} "$1/"
  sed -i "s/^width = .*/width = $4/; s/^height = .*/height = $5/" "$1/scene.toml"
  [ "$3" = "-" ] || sed -i "/newmtl white/,/^Kd/ s/^Kd .*/Kd $3 $3 $3/" "$1"/*.mtl
}
variant room room - 256 256
variant room95s room 0.95 128 128
variant cornells cornell - 128 128
variant cornell95s cornell 0.95 128 128
mkdir -p gallery && cp "$ROOT/scenes/gallery/scene.toml" gallery/
ln -sf "$ROOT/scenes/gallery/gallery.obj" "$ROOT/scenes/gallery/gallery.mtl" gallery/
sed -i "s/^width = .*/width = 192/; s/^height = .*/height = 128/" gallery/scene.toml

# References (kept when OUT_DIR already holds them: they do not depend on the solver).
ref() { [ -f "ref_$1.exr" ] && return; "$M" render "$1/scene.toml" --method pathtrace --spp "$2" -o "ref_$1.exr" > "ref_$1.log" 2>/dev/null; }
ref room 8192; ref room95s 16384; ref cornells 8192; ref cornell95s 8192; ref gallery 16384

# The defaults, scene by scene, over 4 × 4 blocks; at Kd 0.95 the bias over seeds 1-10.
: > defaults.txt
for s in room room95s cornells cornell95s gallery; do
  "$M" render "$s/scene.toml" -o "now_$s.exr" > "now_$s.log" 2>/dev/null
  echo "== $s: $(grep -E '^total' "now_$s.log")" >> defaults.txt
  "$M" compare "now_$s.exr" "ref_$s.exr" --block 4 >> defaults.txt
done
: > seeds.txt
for s in room95s cornell95s; do
  for seed in 1 2 3 4 5 6 7 8 9 10; do
    "$M" render "$s/scene.toml" --seed $seed -o "seed_$s.exr" > /dev/null 2>&1
    echo "== $s seed $seed: $("$M" compare "seed_$s.exr" "ref_$s.exr" --block 4 | grep -i bias)" >> seeds.txt
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
