#!/usr/bin/env bash
# Dev-only (not run by set-up or CI): vendor three.js for the catalog's 3D view into rik/web/static/vendor/three/.
# Takes the npm tarball three@VERSION (`npm pack`, or a .tgz already downloaded given as $1), checks its sha512
# against the registry's integrity, copies the ES-module build and the addons the viewer uses, rewrites the
# addons' bare `from 'three'` imports to relative paths (so no import map and no inline script is needed), and
# writes SOURCE.txt with the version, tarball URL, integrity, the edit and each file's sha256
# (tests/test_web_viewer3d.py checks the files against that list).
#
#   bash scripts/vendor-three.sh                 # downloads with npm pack
#   bash scripts/vendor-three.sh three-0.187.0.tgz
set -euo pipefail
VERSION=0.187.0
INTEGRITY="sha512-Qiu7R+Cmh8CstZsY1uJOSWnVlfo7ZtNLV7mF8Jltk3LB3AtDu9cRZlcnRKkAk8Y4z6KKw35z7Y7Urd7jWY8etA=="
URL="https://registry.npmjs.org/three/-/three-$VERSION.tgz"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$root/rik/web/static/vendor/three"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

if [[ $# -ge 1 ]]; then
  tgz="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
else
  (cd "$work" && npm pack "three@$VERSION" >/dev/null)
  tgz="$work/three-$VERSION.tgz"
fi
got="sha512-$(openssl dgst -sha512 -binary "$tgz" | base64 -w0)"
if [[ "$got" != "$INTEGRITY" ]]; then
  echo "vendor-three: $tgz has integrity $got, expected $INTEGRITY" >&2
  exit 1
fi
tar -xzf "$tgz" -C "$work"
pkg="$work/package"

rm -rf "$dest"
mkdir -p "$dest/addons/controls" "$dest/addons/loaders" "$dest/addons/utils" "$dest/addons/environments"
cp "$pkg/LICENSE" "$dest/LICENSE"
cp "$pkg/build/three.module.js" "$pkg/build/three.core.js" "$dest/"
cp "$pkg/examples/jsm/controls/OrbitControls.js" "$dest/addons/controls/"
cp "$pkg/examples/jsm/loaders/GLTFLoader.js" "$dest/addons/loaders/"
cp "$pkg/examples/jsm/utils/BufferGeometryUtils.js" "$pkg/examples/jsm/utils/SkeletonUtils.js" "$dest/addons/utils/"
cp "$pkg/examples/jsm/environments/RoomEnvironment.js" "$dest/addons/environments/"
sed -i "s#from 'three';#from '../../three.module.js';#" "$dest"/addons/*/*.js
if grep -rn "from 'three'" "$dest/addons"; then
  echo "vendor-three: a bare 'three' import is left (above)" >&2
  exit 1
fi

files=(three.module.js three.core.js addons/controls/OrbitControls.js addons/loaders/GLTFLoader.js
       addons/utils/BufferGeometryUtils.js addons/utils/SkeletonUtils.js addons/environments/RoomEnvironment.js LICENSE)
{
  echo "three.js $VERSION (MIT, see LICENSE), vendored for the catalog's 3D view (rik/web/static/viewer3d.js)."
  echo
  echo "source:    $URL"
  echo "integrity: $INTEGRITY (checked by scripts/vendor-three.sh)"
  echo "taken:     build/three.module.js, build/three.core.js, and from examples/jsm/: controls/OrbitControls.js,"
  echo "           loaders/GLTFLoader.js (+ utils/BufferGeometryUtils.js, utils/SkeletonUtils.js it imports),"
  echo "           environments/RoomEnvironment.js, put under addons/"
  echo "edit:      in addons/*/*.js only: sed \"s#from 'three';#from '../../three.module.js';#\" (the bare"
  echo "           specifier needs an import map, an inline script; relative paths need none)"
  echo
  echo "Why three.js: static ES modules served by rik's own app (behind its launch token, no second server or port),"
  echo "nothing to install at set-up (no npm, works offline and in the wheel), no eval and no inline script (fits a"
  echo "strict CSP), current WebGL2 with OrbitControls and GLTFLoader. Rejected: viser (its own websocket server"
  echo "outside rik's gate, 7 more dependencies), MuJoCo's WebAssembly build (11 MB, physics only, no renderer),"
  echo "Debian's libjs-three (r111 of 2019, Debian-only), trimesh's bundled r140 (inline in an HTML template)."
  echo "Loaded lazily: only when a detail panel opens a 3D view."
  echo
  echo "sha256 of each file, as vendored:"
  (cd "$dest" && sha256sum "${files[@]}")
} > "$dest/SOURCE.txt"
echo "vendored three $VERSION into $dest"
