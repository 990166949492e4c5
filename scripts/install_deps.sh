#!/usr/bin/env bash
# Installs the Debian packages listed in scripts/packages.txt that are not installed yet.
# Fast no-op when everything is present. Runs as root, or as a user with sudo.
#   bash scripts/install_deps.sh
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
list="${here}/packages.txt"
[[ -r "${list}" ]] || { echo "install_deps: cannot read ${list}" >&2; exit 1; }

# Package names: strip comments and blanks.
mapfile -t wanted < <(sed -e 's/#.*//' -e 's/[[:space:]]//g' "${list}" | grep -v '^$' | sort -u)
if ((${#wanted[@]} == 0)); then
  echo "install_deps: ${list} lists no packages"
  exit 0
fi

# One dpkg-query call for all of them; unknown packages go to stderr and make it exit 1.
installed="$(dpkg-query -W -f='${Package} ${Status}\n' "${wanted[@]}" 2>/dev/null || true)"
missing=()
for pkg in "${wanted[@]}"; do
  if ! grep -qE "^${pkg//+/\\+} install ok installed$" <<<"${installed}"; then
    missing+=("${pkg}")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install_deps: all ${#wanted[@]} packages from scripts/packages.txt are installed"
  exit 0
fi

if [[ "$(id -u)" -eq 0 ]]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "install_deps: missing packages and not root, and sudo is not available:" >&2
  echo "  ${missing[*]}" >&2
  exit 1
fi

echo "install_deps: ${#missing[@]} of ${#wanted[@]} packages missing: ${missing[*]}"
echo "install_deps: ${sudo[*]:+${sudo[*]} }apt-get update"
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
echo "install_deps: ${sudo[*]:+${sudo[*]} }apt-get install -y --no-install-recommends ${missing[*]}"
"${sudo[@]}" env DEBIAN_FRONTEND=noninteractive \
  apt-get install -y --no-install-recommends "${missing[@]}"
echo "install_deps: installed ${missing[*]}"
