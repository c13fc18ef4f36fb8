#!/usr/bin/env bash
# Renders an HTML page to a PNG with headless Chromium (Debian's `chromium` package, installed
# when missing: root only, as on the project's machines): `scripts/render-html.sh PAGE.html
# OUT.png [WIDTH HEIGHT]`. The page is loaded from the file; no network is used.
set -euo pipefail
page="$1"
out="$2"
width="${3:-1200}"
height="${4:-6000}"
if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" -ne 0 ]; then
        echo "render-html: chromium is not installed; install Debian's package: apt-get install chromium" >&2
        exit 2
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
profile="$(mktemp -d)"
trap 'rm -rf "$profile"' EXIT
# The flags keep Chromium off the (closed) network and out of the user's profile.
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$profile" --hide-scrollbars --window-size="$width,$height" \
    --screenshot="$(realpath -m "$out")" "file://$(realpath "$page")" 2>/dev/null
test -s "$out"
echo "rendered $page to $out (${width}x${height})"
