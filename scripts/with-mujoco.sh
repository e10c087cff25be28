#!/usr/bin/env bash
# Runs a command with MuJoCo 3.17.0's C library where the `mujoco` feature needs it: at
# build time (MUJOCO_DYNAMIC_LINK_DIR, read by the mujoco-rs crate) and at run time
# (LD_LIBRARY_PATH). The library comes from the `mujoco==3.17.0` wheel of the Python
# package registry (pip, no other package), unpacked once into .mujoco/ of the checkout
# (or $GRASP_MUJOCO_DIR). Linux x86_64 and aarch64, as the wheels are.
#
#   scripts/with-mujoco.sh cargo build --release --features mujoco
#   scripts/with-mujoco.sh ./target/release/grasp run --backend mujoco --object box_gelatin
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dir="${GRASP_MUJOCO_DIR:-$root/.mujoco}"
version=3.17.0
lib="$dir/lib/libmujoco.so.$version"
if [ ! -f "$lib" ]; then
    echo "with-mujoco: fetching the mujoco==$version wheel's C library into $dir" >&2
    mkdir -p "$dir/wheel" "$dir/lib"
    python3 -m pip download -q --no-deps --only-binary=:all: "mujoco==$version" -d "$dir/wheel" >&2
    whl="$(ls "$dir"/wheel/mujoco-"$version"-*.whl | head -n 1)"
    python3 - "$whl" "$dir/lib" "$version" <<'PY'
import sys, zipfile
whl, out, version = sys.argv[1:]
name = f"mujoco/libmujoco.so.{version}"
with zipfile.ZipFile(whl) as z, open(f"{out}/libmujoco.so.{version}", "wb") as f:
    f.write(z.read(name))
PY
    ln -sf "libmujoco.so.$version" "$dir/lib/libmujoco.so"
    rm -rf "$dir/wheel"
fi
export MUJOCO_DYNAMIC_LINK_DIR="$dir/lib"
export LD_LIBRARY_PATH="$dir/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
exec "$@"
