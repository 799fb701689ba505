#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Fails unless every Debian package the build and the tests use is installed by
# scripts/install-deps.sh: listed there, or pulled in by a listed package (Depends/Pre-Depends,
# recursively). "Used" means: the shared libraries the built programs load (ldd), the headers the
# compiler read (the dependency files it wrote under the build folder), and the programs the tests
# run. Each file is resolved to its package through dpkg's file lists; a file under /usr that no
# package owns (a hand install) fails too. Usage: check_install_deps.sh BUILD_DIR
set -euo pipefail
build="$(cd "${1:?usage: check_install_deps.sh BUILD_DIR}" && pwd)"
repo="$(cd "$(dirname "$0")/../.." && pwd)"
command -v dpkg-query >/dev/null || { echo "check-deps: not a Debian system (no dpkg): skipped"; exit 77; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The packages install-deps.sh lists: the words of its packages=( ... ) array, comments dropped.
sed -n '/^packages=(/,/^)/p' "$repo/scripts/install-deps.sh" | sed -e 's/#.*//' -e 's/packages=(//' -e 's/)//' |
  tr -s ' \t' '\n\n' | sed '/^$/d' | sort -u >"$work/listed"
[ -s "$work/listed" ] || { echo "check-deps: no package list found in scripts/install-deps.sh"; exit 1; }

# Their closure over Depends and Pre-Depends among installed packages (virtual packages resolve to
# their installed providers).
dpkg-query -W -f='${Package} ${Status}\n' | awk '$4 == "installed" {print $1}' | sort -u >"$work/installed"
dpkg-query -W -f='${Package}\t${Provides}\t${Depends}, ${Pre-Depends}\n' >"$work/depends"
awk -F'\t' -v listed="$work/listed" -v installed="$work/installed" '
  BEGIN {
    while ((getline p < installed) > 0) ok[p] = 1
    while ((getline p < listed) > 0) queue[++n] = p
  }
  {
    pkg = $1
    np = split($2, provides, ",")
    for (i = 1; i <= np; i++) { v = provides[i]; sub(/^ */, "", v); sub(/ .*/, "", v); if (v != "" && ok[pkg]) provider[v] = provider[v] " " pkg }
    deps[pkg] = $3
  }
  END {
    for (i = 1; i <= n; i++) {
      p = queue[i]
      if (seen[p]++) continue
      if (!(p in deps) && (p in provider)) { m = split(provider[p], ps, " "); for (j = 1; j <= m; j++) queue[++n] = ps[j]; continue }
      print p
      m = split(deps[p], ds, ",")
      for (j = 1; j <= m; j++) {
        na = split(ds[j], alts, "|")
        for (k = 1; k <= na; k++) {
          d = alts[k]; sub(/^ */, "", d); sub(/[ :(].*/, "", d)
          if (d == "") continue
          if (ok[d] || (d in provider)) { queue[++n] = d; break }
        }
      }
    }
  }' "$work/depends" | sort -u >"$work/closure"

# Files the build and the tests use.
{
  # Headers: every dependency file the compiler wrote (-MD), system paths only.
  find "$build" -name '*.d' -type f -exec cat {} + | tr ' \\' '\n\n' | grep -E '^/(usr|opt)/' || true
  # Shared libraries of every program built (texfab, tests, benchmarks).
  find "$build" -type f -perm -u+x -newer "$build/CMakeCache.txt" -exec sh -c 'head -c 4 "$1" | grep -q ELF' _ {} \; -print |
    while read -r program; do ldd "$program" 2>/dev/null | awk '/=> \// {print $3} /^\t\// {print $1}'; done
  # Programs the build and the tests run.
  for tool in cmake make g++ pkg-config node npm assimp blender qemu-x86_64 prusa-slicer; do
    if path="$(command -v "$tool")"; then echo "$path"; fi
  done
} | sort -u >"$work/files"

# dpkg's owner of each file (also under its resolved path and with /usr merged or not).
awk '
  FNR == 1 { pkg = FILENAME; sub(/.*\//, "", pkg); sub(/\.list$/, "", pkg); sub(/:.*/, "", pkg) }
  { owner[$0] = pkg }
  END {
    while ((getline f < "/dev/stdin") > 0) {
      n = split(f, candidates, "\t")
      found = ""
      for (i = 1; i <= n && found == ""; i++) {
        c = candidates[i]
        if (c in owner) found = owner[c]
        else if (("/usr" c) in owner) found = owner["/usr" c]
        else if (substr(c, 1, 5) == "/usr/" && (substr(c, 5) in owner)) found = owner[substr(c, 5)]
      }
      print (found == "" ? "?" : found) "\t" candidates[1]
    }
  }' /var/lib/dpkg/info/*.list < <(xargs -d '\n' realpath -m -- <"$work/files" | paste "$work/files" -) |
  sort -u >"$work/owners"

status=0
# Files no package owns: hand installs (but not node/npm from elsewhere, which install-deps accepts).
while IFS=$'\t' read -r pkg file; do
  [ "$pkg" = "?" ] || continue
  case "$file" in
    "$build"/*|"$repo"/*) ;;
    */node|*/npm|*/nodejs) ;;
    *) echo "check-deps: $file belongs to no Debian package (installed by hand?)"; status=1 ;;
  esac
done <"$work/owners"
# Packages used but not installed by install-deps.sh.
cut -f1 "$work/owners" | grep -v '^?$' | sort -u >"$work/used"
while read -r pkg; do
  if ! grep -qx "$pkg" "$work/closure"; then
    example="$(awk -F'\t' -v p="$pkg" '$1 == p {print $2; exit}' "$work/owners")"
    echo "check-deps: package $pkg (e.g. $example) is used but scripts/install-deps.sh does not install it"
    status=1
  fi
done <"$work/used"
echo "check-deps: $(wc -l <"$work/files") files from $(wc -l <"$work/used") packages; install-deps.sh lists $(wc -l <"$work/listed"), $(wc -l <"$work/closure") with their dependencies"
exit $status
