#!/usr/bin/env bash
# Headless-browser check of the episode replay page (`--record`): records one baseline-2
# episode, renders its page in headless Chromium (software WebGL) at a frame of the lift
# with the panels hidden, and checks the screenshot shows the 3D scene: enough pixel
# variance, enough object-orange pixels and enough hand-blue pixels.
#
# Installs nothing. Needs Debian's chromium (`apt-get install -y chromium`) and python3
# (standard library only). Without chromium it prints SKIP and exits 0, unless
# REQUIRE_CHROMIUM=1 (then it fails). Usage: tests/viewer_screenshot.sh [OUT_DIR]
# The screenshot is left in OUT_DIR (default: a temporary folder) as shot.png.
set -euo pipefail
cd "$(dirname "$0")/.."

browser=""
for b in chromium chromium-browser google-chrome; do
    if command -v "$b" > /dev/null 2>&1; then
        browser="$b"
        break
    fi
done
if [ -z "$browser" ]; then
    if [ "${REQUIRE_CHROMIUM:-0}" = "1" ]; then
        echo "FAIL: no chromium found" >&2
        exit 1
    fi
    echo "SKIP: no chromium found (apt-get install -y chromium)"
    exit 0
fi

out="${1:-$(mktemp -d)}"
mkdir -p "$out"
rec="$out/rec"
rm -rf "$rec"
cargo run --release -q -- -q rollout --policy baseline2 --objects can_soup --episodes 1 \
    --record "$rec" > /dev/null
page="$(ls "$rec"/*.html | grep -v index.html | head -n 1)"
shot="$out/shot.png"
rm -f "$shot"
# Frame 150 of 233 lies in the lift; the page renders once at load, so a short virtual
# time budget is enough.
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --use-angle=swiftshader \
    --enable-unsafe-swiftshader --hide-scrollbars --window-size=800,600 \
    --virtual-time-budget=3000 --screenshot="$shot" \
    "file://$(realpath "$page")#frame=150&noui" > "$out/chromium.log" 2>&1 || true
if [ ! -s "$shot" ]; then
    echo "FAIL: chromium wrote no screenshot (log: $out/chromium.log)" >&2
    exit 1
fi

python3 - "$shot" << 'EOF'
import struct, sys, zlib

def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, "unsupported PNG"
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride = zlib.decompress(idat), w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return w, h, [(r[i], r[i + 1], r[i + 2]) for r in rows for i in range(0, stride, bpp)]

w, h, px = read_png(sys.argv[1])
n = len(px)
lum = [0.299 * r + 0.587 * g + 0.114 * b for r, g, b in px]
mean = sum(lum) / n
std = (sum((l - mean) ** 2 for l in lum) / n) ** 0.5
orange = sum(1 for r, g, b in px if r > 150 and 60 < g < 200 and b < 90 and r - b > 100)
blue = sum(1 for r, g, b in px if b > 90 and b - r > 25 and b - g > 5)
print(f"screenshot {w}x{h}: luminance std {std:.1f}, object pixels {orange}, hand pixels {blue}")
ok = std > 10 and orange > 0.002 * n and blue > 0.01 * n
print("OK" if ok else "FAIL: the page does not show the hand and the object")
sys.exit(0 if ok else 1)
EOF
