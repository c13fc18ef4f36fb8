#!/bin/sh
# Splits a measurement CSV (docs/formats.md#measurement-csv) into a training file (every axis
# experiment, the tool experiment and the free poses of experiment `validation` at even steps)
# and a test file (the free poses at odd steps), both with the file's comment and header lines.
# Usage: scripts/split-validation.sh DATA.csv TRAIN.csv TEST.csv
set -eu
[ $# -eq 3 ] || { echo "usage: $0 DATA.csv TRAIN.csv TEST.csv" >&2; exit 2; }
awk -F, -v train="$2" -v test="$3" '
  /^#/ || !seen_header { print > train; print > test; if (!/^#/) { seen_header = 1; for (i = 1; i <= NF; i++) col[$i] = i }; next }
  $col["experiment"] == "validation" { if ($col["step"] % 2 == 0) print > train; else print > test; next }
  { print > train }
' "$1"
