#!/usr/bin/env bash
# Builds the QEMU TCG plugin insncount.c into OUT_DIR (default: targets/target/plugin):
#
#   targets/plugin/build.sh [OUT_DIR]      prints the path of libinsncount.so
#
# Debian ships QEMU 7.2 with plugin support (-plugin) but no plugins and no plugin header, so
# the header comes from Debian's source package of the installed qemu-system-arm: a private
# apt configuration under OUT_DIR (the system's sources are untouched) adds the bookworm
# deb-src lines, `apt-get source --download-only` fetches the package, and qemu-plugin.h is
# taken from it. The header is kept in OUT_DIR, so later builds need no network.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-$here/../target/plugin}
mkdir -p "$out"
out=$(cd "$out" && pwd)

need=()
command -v gcc >/dev/null || need+=(gcc libc6-dev)
command -v xz >/dev/null || need+=(xz-utils)
command -v dpkg-source >/dev/null || need+=(dpkg-dev)
[ -e /usr/share/keyrings/debian-archive-keyring.gpg ] || need+=(debian-archive-keyring)
if [ ${#need[@]} -gt 0 ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi

ver=$(dpkg-query -W -f='${source:Version}' qemu-system-arm)   # e.g. 1:7.2+dfsg-7+deb12u18
header="$out/qemu-$ver/qemu-plugin.h"
if [ ! -s "$header" ]; then
  apt="$out/apt"
  mkdir -p "$apt/lists/partial" "$apt/cache/archives/partial" "$apt/src"
  key=/usr/share/keyrings/debian-archive-keyring.gpg
  cat > "$apt/sources.list" <<EOS
deb-src [signed-by=$key] http://deb.debian.org/debian bookworm main
deb-src [signed-by=$key] http://deb.debian.org/debian bookworm-updates main
deb-src [signed-by=$key] http://deb.debian.org/debian-security bookworm-security main
EOS
  cat > "$apt/apt.conf" <<EOS
Dir::Etc::SourceList "$apt/sources.list";
Dir::Etc::SourceParts "/dev/null";
Dir::State::Lists "$apt/lists";
Dir::Cache "$apt/cache";
EOS
  # As root, apt would hand the download to the _apt user, who cannot write here.
  [ "$(id -u)" -ne 0 ] || echo 'APT::Sandbox::User "root";' >> "$apt/apt.conf"
  echo "fetching Debian's source of qemu $ver for qemu-plugin.h" >&2
  APT_CONFIG="$apt/apt.conf" apt-get -qq update
  (cd "$apt/src" && APT_CONFIG="$apt/apt.conf" apt-get -qq source --download-only "qemu=$ver")
  mkdir -p "$(dirname "$header")"
  tar -xJf "$apt"/src/qemu_*.orig.tar.xz -C "$apt/src" --wildcards '*/include/qemu/qemu-plugin.h'
  cp "$apt"/src/qemu-*/include/qemu/qemu-plugin.h "$header"
  rm -rf "$apt"
fi
gcc -O2 -Wall -Wextra -Wno-unused-parameter -shared -fPIC -I"$(dirname "$header")" \
  -o "$out/libinsncount.so" "$here/insncount.c"
echo "$out/libinsncount.so"
