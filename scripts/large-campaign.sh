#!/usr/bin/env bash
# Write a large measurement CSV for memory and time checks: a simulated campaign whose
# validation rows are repeated with new step numbers (step + 1000 x copy) up to ROWS rows.
#
# Usage: scripts/large-campaign.sh ROWS OUT.csv [free]
#   free: the validation rows only (a free-pose file, no axis experiment)
#
# Environment:
#   AXISCAL  the binary (default target/release/axiscal)
#   SEED     the campaign's seed (default 3)
#
# e.g. scripts/large-campaign.sh 1000000 big.csv && /usr/bin/time -v target/release/axiscal diagnose big.csv --out d
set -euo pipefail
rows="${1:?usage: scripts/large-campaign.sh ROWS OUT.csv [free]}"
out="${2:?usage: scripts/large-campaign.sh ROWS OUT.csv [free]}"
kind="${3:-}"
axiscal="${AXISCAL:-target/release/axiscal}"
base="$(mktemp --suffix=.csv)"
trap 'rm -f "$base"' EXIT
"$axiscal" simulate --sim analytic --seed "${SEED:-3}" --out "$base" --force >/dev/null
awk -F, -v OFS=, -v rows="$rows" -v free="$kind" '
    /^#/ || $1 == "experiment" { print; next }
    free == "free" && $1 != "validation" { next }
    { print; n++; if ($1 == "validation") v[++nv] = $0 }
    END {
        for (copy = 1; n < rows && nv > 0; copy++)
            for (i = 1; i <= nv && n < rows; i++) { $0 = v[i]; $3 = $3 + 1000 * copy; print; n++ }
    }' "$base" > "$out"
echo "wrote $out ($(($(wc -l < "$out") - 2)) rows)"
