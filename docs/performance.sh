#!/bin/bash
# Re-measures the first tables of docs/performance.md on this machine: the room end to end,
# the presets against path-traced references, one thread against two, the cluster threshold,
# and how the solve scales. About 25 minutes on 2 cores, the references most of it (OUT_DIR
# keeps them: they do not depend on the solver).
# Usage: docs/performance.sh OUT_DIR
set -euo pipefail
OUT=${1:?usage: docs/performance.sh OUT_DIR}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cargo build --release --manifest-path "$ROOT/Cargo.toml"
[ -f "$ROOT/scenes/gallery/gallery.obj" ] || (cd "$ROOT" && cargo run --release -p meshlight-gallery)
M="$ROOT/target/release/meshlight"
TIME="/usr/bin/time -f %e-s-wall-%M-KB"
mkdir -p "$OUT" && cd "$OUT"

# The room end to end: README command 1's render, its summary as printed.
"$M" render "$ROOT/scenes/room/scene.toml" -o room.exr > room.txt 2>/dev/null

# Scene variants for the presets: `room` at 256², `cornell` at 128², the gallery at 192×128.
variant() { # name source-dir width height
  mkdir -p "$1" && cp "$ROOT/scenes/$2"/*.{obj,mtl,toml} "$1/" 2>/dev/null || true
  cp "$ROOT/scenes/$2/scene.toml" "$1/"
  sed -i "s/^width = .*/width = $3/; s/^height = .*/height = $4/" "$1/scene.toml"
}
variant room room 256 256
variant cornell cornell 128 128
mkdir -p gallery && cp "$ROOT/scenes/gallery/scene.toml" gallery/
ln -sf "$ROOT/scenes/gallery/gallery.obj" "$ROOT/scenes/gallery/gallery.mtl" gallery/
sed -i "s/^width = .*/width = 192/; s/^height = .*/height = 128/" gallery/scene.toml
ref() { [ -f "ref_$1.exr" ] && return; "$M" render "$1/scene.toml" --method pathtrace --spp "$2" -o "ref_$1.exr" > "ref_$1.log" 2>/dev/null; }
ref room 4096; ref cornell 8192; ref gallery 8192
"$M" sweep room/scene.toml --reference ref_room.exr --vary preset=preview,default,final --no-pathtrace --block 4 --out presets_room > presets_room.txt 2>/dev/null
"$M" sweep cornell/scene.toml --reference ref_cornell.exr --vary preset=preview,default,final --no-pathtrace --block 4 --out presets_cornell > presets_cornell.txt 2>/dev/null
"$M" sweep gallery/scene.toml --reference ref_gallery.exr --vary preset=preview,default,final --no-pathtrace --block 4 --out presets_gallery > presets_gallery.txt 2>/dev/null

# One thread against two: the render of the room (256², at the defaults and at the cheapest
# preview) and of the gallery (768×512), each timed at 1 and 2 threads in turn, against the
# same rays cast on their own; the images must be the same bit for bit.
"$M" bench-render room/scene.toml --width 256 --height 256 --quiet > threads_room.txt 2>/dev/null
"$M" bench-render room/scene.toml --width 256 --height 256 --preset preview --epsilon-scale 3 \
  --repeats 9 --quiet > threads_room_preview.txt 2>/dev/null
"$M" bench-render "$ROOT/scenes/gallery/scene.toml" --repeats 3 --quiet > threads_gallery.txt 2>/dev/null

# The cluster threshold against the flat solve of the same settings.
: > threshold.txt
for s in "$ROOT/scenes/room/scene.toml" "$ROOT/scenes/gallery/scene.toml"; do
  for t in 0 0.01 0.05 0.2 1; do
    $TIME "$M" render "$s" --cluster-threshold $t -o "threshold_$t.exr" > "threshold_$t.log" 2> "threshold_$t.time"
    echo "$s threshold $t: $(tail -1 "threshold_$t.time") $(grep -E '^solver' "threshold_$t.log")" >> threshold.txt
    [ "$t" = 0 ] || "$M" compare "threshold_$t.exr" threshold_0.exr | head -2 >> threshold.txt
  done
done

# How the solve scales with the samples, hierarchy and flat.
"$M" scale "$ROOT/scenes/gallery/scene.toml" --epsilon 0.6,0.3,0.15,0.075 --rounds 0 > scale.txt 2>/dev/null
echo "done: $OUT"
