#!/usr/bin/env bash
# Validates the GitHub Actions workflows (.github/workflows/*.yml) against the Actions schema with
# @action-validator/cli, the version pinned in scripts/dist/lint/package-lock.json (installed with
# `npm ci` into WORKDIR on first use; no global install).
#
#   scripts/dist/lint-workflows.sh [WORKDIR (default build/workflow-lint)] [FILE.yml ...]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${1:-$root/build/workflow-lint}
shift || true
command -v npm >/dev/null || { echo "lint-workflows: npm not installed (scripts/install-deps.sh)" >&2; exit 3; }
mkdir -p "$work"
if ! cmp -s "$root/scripts/dist/lint/package-lock.json" "$work/package-lock.json" || [[ ! -x "$work/node_modules/.bin/action-validator" ]]; then
  cp "$root/scripts/dist/lint/package.json" "$root/scripts/dist/lint/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) ||
    { echo "lint-workflows: npm ci failed in $work" >&2; exit 3; }
fi
files=("$@")
[[ ${#files[@]} -gt 0 ]] || files=("$root"/.github/workflows/*.yml)
status=0
for f in "${files[@]}"; do
  if "$work/node_modules/.bin/action-validator" "$f" >"$work/last.log" 2>&1; then
    echo "lint-workflows: $f ok"
  else
    echo "lint-workflows: $f INVALID" >&2
    grep -v '^WARNING: Glob validation' "$work/last.log" >&2 || true
    status=1
  fi
done
exit $status
