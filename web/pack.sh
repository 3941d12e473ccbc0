#!/usr/bin/env bash
# Makes the npm package @tsm-codec/decoder from a wasm build (web/build.sh):
# build/web/package/ (web/package/ + the decoder, the JS API and the three.js
# plugin from build/web/), packed by `npm pack` into build/web/tsm-codec-decoder-VERSION.tgz.
# The version is the project's (CMakeLists.txt). Prints the tarball's path.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${TSM_WEB_OUT:-$ROOT/build/web}"
for f in tsm_decoder.js tsm_decoder.wasm tsm_decoder_full.js tsm_decoder_full.wasm; do
  [ -f "$OUT/$f" ] || { echo "web/pack.sh: $OUT/$f missing: run web/build.sh first" >&2; exit 1; }
done
VERSION="$(sed -n 's/^project(tsm VERSION \([0-9.]*\).*/\1/p' "$ROOT/CMakeLists.txt")"
PKG="$OUT/package"
rm -rf "$PKG" && mkdir -p "$PKG"
cp "$ROOT"/web/package/{package.json,README.md,tsm.d.ts,gltf-tsm-extension.d.ts} "$PKG/"
cp "$OUT"/tsm_decoder{,_full}.{js,wasm} "$ROOT"/web/{tsm.js,tsm-worker.js,gltf-tsm-extension.js} "$PKG/"
node -e 'const f=process.argv[1], p=JSON.parse(require("fs").readFileSync(f)); p.version=process.argv[2];
  require("fs").writeFileSync(f, JSON.stringify(p, null, 2) + "\n")' "$PKG/package.json" "$VERSION"
(cd "$PKG" && npm pack --silent --pack-destination "$OUT" >/dev/null)
echo "$OUT/tsm-codec-decoder-$VERSION.tgz"
