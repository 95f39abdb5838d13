#!/usr/bin/env bash
# Fails (exit 1, listing path:line: text) when a file of the tree cites a document or an issue that
# is not in the repository: the product specification by its section ("SPEC" and a section sign),
# the prototype performance notes by name, an issue by number ("issue 11", a test named Issue11...,
# "the issue's case"), or any section sign (a paper's or a spec's section). Comments and docs point
# at docs/ instead (docs/model.md, docs/storage.md, docs/update-job.md, docs/performance.md), or
# cite a published work by its authors, title and equation number.
#   scripts/check-citations.sh [ROOT]      ROOT: the source tree (default: this script's parent)
# Reads every text file git knows of (tracked, and untracked but not ignored); outside a git
# checkout, every file except build trees and hidden directories. This script is left out: it has
# to spell the patterns. Registered as the ctest test meta.no_external_citations.
set -euo pipefail
export LC_ALL=C  # byte-wise matching: the section sign is matched as its two UTF-8 bytes
root=$(cd "${1:-$(dirname "$0")/..}" && pwd)
cd "$root"
self=scripts/check-citations.sh

# Word-bounded, so that enum values such as MAP_KIND_UNSPECIFIED do not count.
pattern='(^|[^A-Za-z0-9_])SPEC([^A-Za-z0-9_]|$)|PERF-NOTES|[Ii]ssue ?#?[0-9]+|[Tt]he issue('"'"'s|:)|§'

list_files() {
  if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git ls-files -z --cached --others --exclude-standard
  else
    find . \( -name '.?*' -o -name 'build' -o -name 'build-*' \) -prune -o -type f -print0 | sed -z 's|^\./||'
  fi
}

# -I: binary files (pictures, fuzz corpora) are skipped; -s: a tracked file deleted in the work
# tree is no error. grep exits 1 when nothing matches, which is the good case.
hits=$(list_files | grep -zvxF -e "$self" | xargs -0 -r grep -sInHE -e "$pattern" -- || true)

if [[ -n "$hits" ]]; then
  printf '%s\n' "$hits"
  count=$(printf '%s\n' "$hits" | wc -l)
  echo "check-citations: $count line(s) cite a document or issue that is not in the repository;" \
       "point at docs/ instead (see $self)" >&2
  exit 1
fi
echo "check-citations: no external citations in $root"
