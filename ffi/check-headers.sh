#!/usr/bin/env bash
# Compile-only check of the C shim against both Embree APIs it supports:
#  - Embree 3 from the installed libembree-dev (Debian 12), if present;
#  - Embree 4 (Debian 13's package) from the headers the `embree4-sys` crate's source carries,
#    fetched from crates.io into cargo's registry. Nothing is linked or run.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cc=${CC:-cc}
flags=(-std=c11 -Wall -Wextra -Werror -fsyntax-only)

if [ -f /usr/include/embree3/rtcore.h ]; then
  "$cc" "${flags[@]}" -DML_EMBREE_MAJOR=3 "$here/shim.c"
  echo "shim.c compiles against Embree 3 (/usr/include/embree3)"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/src"
: > "$work/src/lib.rs"
cat > "$work/Cargo.toml" <<'TOML'
[package]
name = "embree4-headers"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
embree4-sys = "=0.0.12"
TOML
(cd "$work" && cargo fetch --quiet)
header=$(find "${CARGO_HOME:-$HOME/.cargo}/registry/src" -path '*/embree4-sys-0.0.12/lib/embree4/rtcore.h' -print -quit)
if [ -z "$header" ]; then
  echo "embree4-sys headers not found after cargo fetch" >&2
  exit 1
fi
include=$(dirname "$(dirname "$header")")
"$cc" "${flags[@]}" -DML_EMBREE_MAJOR=4 -I"$include" "$here/shim.c"
echo "shim.c compiles against Embree 4 ($include/embree4)"
