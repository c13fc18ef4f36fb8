#!/bin/bash
# Regenerates every case and diagnoses it.  Usage: bash run_all.sh
set -e
cd "$(dirname "$0")"
python3 mkdesc.py
./axiscal plan --robot pg-arm.toml --plan pg-plan.toml --no-sight --validation-poses 0 --out plan.csv --force
while read -r name args; do
  [ -z "$name" ] && continue
  python3 gen.py $args --out cases/$name.csv 2> cases/$name.gen.txt
  ./axiscal diagnose --robot pg-arm.toml cases/$name.csv --out out/$name --force --quiet > out/$name.console.txt 2>&1
  echo "$name: $(cat cases/$name.gen.txt | sed 's/^.*poses; //') | $(grep -v '^noise estimated\|^wrote\|^  with' out/$name.console.txt | head -1)"
done < cases.txt
./axiscal calibrate --robot pg-arm.toml cases/none.csv --out cal/none --force > cal/none.console.txt 2>&1
./axiscal validate --calibration cal/none/calibration.json --robot pg-arm.toml cases/none.csv --out cal/none-val --force > cal/none-val.console.txt 2>&1
python3 summarize.py > results.md
