#!/usr/bin/env bash
# Fetch the real C. elegans clips of §6 (issue 4): the omega-turn and delta-turn kymograms of the
# `elegansbot` package (PyPI, sdist 1.0.2), pinned by the sdist's sha256. Writes
#   data/elegansbot/kymogram_omega-turn.npy   600 frames x 24 joint angles [rad], 32 frames/s
#   data/elegansbot/kymogram_delta-turn.npy   300 frames x 24 joint angles [rad], 32 frames/s
#   data/elegansbot/README.md                 the package's examples/README.md (provenance)
#   data/elegansbot/SOURCE.txt                package, version, sdist file name and sha256
# data/ is gitignored: the data are never committed. Idempotent: does nothing when the three
# files are present and SOURCE.txt records the pinned sha256. Needs python3 with pip and tar.
set -euo pipefail
cd "$(dirname "$0")/.."

PKG=elegansbot
VERSION=1.0.2
SHA256=16ad4cd055b420ea45f42a9d4c914a58405da5373c6a47bac71b67c3807152ca
DEST=data/elegansbot
FILES=(examples/kymogram_omega-turn.npy examples/kymogram_delta-turn.npy examples/README.md)

have_all() {
  [ -f "$DEST/SOURCE.txt" ] && grep -q "^sha256 $SHA256\$" "$DEST/SOURCE.txt" || return 1
  for f in "${FILES[@]}"; do [ -s "$DEST/$(basename "$f")" ] || return 1; done
}
if have_all; then
  echo "worm data: present in $DEST ($PKG $VERSION, sdist sha256 $SHA256)"
  exit 0
fi

PY=$(command -v python3 || true)
if [ -z "$PY" ] || ! "$PY" -m pip --version >/dev/null 2>&1; then
  echo "fetch_worm_data.sh: python3 with pip is needed (Debian: apt-get install python3-pip; scripts/install_deps.sh does this)" >&2
  exit 1
fi

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
echo "worm data: downloading the $PKG $VERSION sdist from PyPI"
"$PY" -m pip download --quiet --disable-pip-version-check --no-deps --no-binary :all: \
  "$PKG==$VERSION" -d "$TMP"
shopt -s nullglob
sdists=("$TMP"/*.tar.gz)
if [ ${#sdists[@]} -ne 1 ]; then
  echo "fetch_worm_data.sh: expected one sdist (*.tar.gz) from pip download, got: $(ls "$TMP")" >&2
  exit 1
fi
SDIST=${sdists[0]}
got=$(sha256sum "$SDIST" | cut -d' ' -f1)
if [ "$got" != "$SHA256" ]; then
  echo "fetch_worm_data.sh: CHECKSUM MISMATCH for $(basename "$SDIST"):" >&2
  echo "  expected sha256 $SHA256" >&2
  echo "  got      sha256 $got" >&2
  echo "  refusing to use it; nothing was written to $DEST" >&2
  exit 1
fi

# The sdist has one top-level folder, $PKG-$VERSION/.
TOP="$PKG-$VERSION"
tar -tzf "$SDIST" > "$TMP/listing.txt"
members=()
for f in "${FILES[@]}"; do
  if ! grep -qxF "$TOP/$f" "$TMP/listing.txt"; then
    echo "fetch_worm_data.sh: $(basename "$SDIST") has no member $TOP/$f" >&2
    exit 1
  fi
  members+=("$TOP/$f")
done
tar -xzf "$SDIST" -C "$TMP" "${members[@]}"
mkdir -p "$DEST"
for f in "${FILES[@]}"; do
  cp "$TMP/$TOP/$f" "$DEST/$(basename "$f").part"
  mv "$DEST/$(basename "$f").part" "$DEST/$(basename "$f")"
done
printf 'package %s\nversion %s\nsdist %s\nsha256 %s\nsource https://pypi.org/project/%s/%s/\n' \
  "$PKG" "$VERSION" "$(basename "$SDIST")" "$SHA256" "$PKG" "$VERSION" > "$DEST/SOURCE.txt"
echo "worm data: wrote $DEST ($(cd "$DEST" && ls | tr '\n' ' '))"
