#!/usr/bin/env bash
# vendor/rapier3d as the published rapier3d 0.36.1 plus the patch series in
# vendor/patches/rapier3d/ (see vendor/README.md).
#
#   vendor/patches/rapier3d.sh check      re-creates the patched tree in a temporary
#                                         folder and compares it with vendor/rapier3d
#                                         (exit 0 when identical, 1 otherwise)
#   vendor/patches/rapier3d.sh apply DIR  re-creates the patched tree into DIR (which
#                                         must not exist yet)
#
# The published crate comes from crates.io through cargo itself: `cargo vendor` of a
# throwaway project that depends on rapier3d =0.36.1, with its own lock file and target
# folder in a temporary folder (the project's Cargo.lock and target/ are not touched,
# nor is vendor/rapier3d). The vendored copy leaves out what the first commit that added
# it left out: the examples, the tests, their [[example]] / [[test]] entries in
# Cargo.toml, the published Cargo.lock and cargo's .cargo_vcs_info.json (and
# .cargo-checksum.json, which `cargo vendor` adds). Then the patches are applied in order.
set -euo pipefail

version=0.36.1
usage() {
    echo "usage: $0 check | apply DIR" >&2
    exit 2
}
[[ $# -ge 1 ]] || usage
mode=$1
case "$mode" in
    check) [[ $# -eq 1 ]] || usage ;;
    apply)
        [[ $# -eq 2 ]] || usage
        dest=$2
        [[ ! -e "$dest" ]] || { echo "$0: $dest exists" >&2; exit 2; }
        # Absolute, before the cd below.
        case "$dest" in /*) ;; *) dest="$PWD/$dest" ;; esac
        ;;
    *) usage ;;
esac

cd "$(dirname "${BASH_SOURCE[0]}")/../.."
repo=$PWD
series_dir="$repo/vendor/patches/rapier3d"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# 1. The published crate, as cargo downloads it (checksum verified against the index).
mkdir -p "$work/fetch/src"
cat > "$work/fetch/Cargo.toml" <<EOF
[package]
name = "rapier3d-published"
version = "0.0.0"
edition = "2021"
publish = false

[dependencies]
rapier3d = "=$version"

[workspace]
EOF
: > "$work/fetch/src/lib.rs"
(cd "$work/fetch" && CARGO_TARGET_DIR="$work/fetch/target" \
    cargo vendor --quiet --versioned-dirs "$work/crates" > /dev/null)
published="$work/crates/rapier3d-$version"
[[ -f "$published/Cargo.toml" ]] || { echo "$0: cargo vendor gave no rapier3d-$version" >&2; exit 1; }

# 2. The vendored layout: no examples, tests, lock file or cargo metadata, and no
# [[example]] / [[test]] / [[bench]] tables in the manifest.
tree="$work/rapier3d"
cp -R "$published" "$tree"
rm -rf "$tree/examples" "$tree/tests" "$tree/benches" "$tree/Cargo.lock" \
    "$tree/.cargo-checksum.json" "$tree/.cargo_vcs_info.json"
awk '/^\[\[(example|test|bench)\]\]$/ { skip = 1; next }
     /^\[/ { skip = 0 }
     !skip' "$published/Cargo.toml" > "$tree/Cargo.toml"

# 3. The series, in order. git apply works outside a repository; the ceiling keeps it
# from finding one above the temporary folder.
n=0
for p in "$series_dir"/[0-9][0-9][0-9][0-9]-*.patch; do
    [[ -e "$p" ]] || { echo "$0: no patches in $series_dir" >&2; exit 1; }
    if ! (cd "$tree" && GIT_CEILING_DIRECTORIES="$work" \
        git apply --whitespace=nowarn "$p"); then
        echo "$0: $(basename "$p") does not apply to rapier3d $version + the $n before it" >&2
        exit 1
    fi
    n=$((n + 1))
done

case "$mode" in
    apply)
        cp -R "$tree" "$dest"
        echo "$dest = rapier3d $version + $n patches"
        ;;
    check)
        # target/ and Cargo.lock are what `cd vendor/rapier3d && cargo test` leaves there
        # (ignored by .gitignore).
        if diff -r -x target -x Cargo.lock "$tree" vendor/rapier3d > "$work/diff" 2>&1; then
            echo "vendor/rapier3d = rapier3d $version + $n patches"
        else
            echo "vendor/rapier3d differs from rapier3d $version + the $n patches of vendor/patches/rapier3d:" >&2
            diff -rq -x target -x Cargo.lock "$tree" vendor/rapier3d | sed "s|$tree|(published + series)|" >&2 || true
            echo "first lines of the difference ('<' published + series, '>' vendor/rapier3d):" >&2
            sed "s|$tree|(published + series)|" "$work/diff" | head -40 >&2
            exit 1
        fi
        ;;
esac
