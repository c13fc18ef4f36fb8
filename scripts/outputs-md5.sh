#!/usr/bin/env bash
# The MD5 of every output of a fixed set of commands, to show that a refactor changes no output
# (ARCHITECTURE.md, "Checking a refactor"). Run it with the binary before and after the change
# and compare the two tables:
#
#   scripts/outputs-md5.sh target/quick-release/axiscal /tmp/before > before.md5
#   scripts/outputs-md5.sh target/quick-release/axiscal /tmp/after  > after.md5
#   diff before.md5 after.md5
#
# The commands: every shipped scenario (4 trials a case, seed 1); `simulate`, `calibrate`,
# `validate`, `compensate`, `diagnose` and `report` on the paper campaign; `calibrate` on the four
# test robots of tests/data/test-robot-spec.toml and on the independent generators' free-pose and
# parallelogram files; 24 blind `diagnose` cases on the analytic arm. Each command's console
# output is kept as a file too. About 30 s on 2 cores. Run from the repository's root.
set -euo pipefail

bin=$(realpath "$1")
out=$2
if [ -e "$out" ]; then
	echo "outputs-md5.sh: $out exists; give a new folder" >&2
	exit 2
fi
mkdir -p "$out"
robots=scenarios/robots
step=0

# One command: its stdout and stderr kept as `NN-NAME.console`, its exit code on the last line.
run() {
	local name=$1
	shift
	step=$((step + 1))
	local log
	log=$(printf '%s/%02d-%s.console' "$out" "$step" "$name")
	set +e
	"$bin" --quiet "$@" >"$log" 2>&1
	echo "exit $?" >>"$log"
	set -e
}

for scenario in scenarios/*.toml; do
	name=$(basename "$scenario" .toml)
	run "run-$name" run "$scenario" --trials 4 --seed 1 --out "$out/run-$name"
done

paper=$out/paper
mkdir -p "$paper"
run simulate-paper simulate --seed 1 --out "$paper/campaign.csv"
run calibrate-paper calibrate "$paper/campaign.csv" --out "$paper/cal"
run validate-paper validate "$paper/campaign.csv" --calibration "$paper/cal/calibration.json" --out "$paper/validation"
printf 'id,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\np1,-3142.3,5341.9,-26.1,180,0,0\np2,-3000,5200,100,180,10,0\n' \
	>"$paper/poses.csv"
run compensate-paper compensate --calibration "$paper/cal/calibration.json" --poses "$paper/poses.csv" --out "$paper/compensated.csv"
run diagnose-paper diagnose "$paper/campaign.csv" --noise-trials 4 --noise-draws 8 --out "$paper/diagnosis"
run report-paper report --calibration "$paper/cal/calibration.json" --data "$paper/campaign.csv" \
	--held-out "$paper/campaign.csv" --instrument "simulated theodolites" --out "$paper/certificate"
run calibrate-paper-refine calibrate "$paper/campaign.csv" --refine --out "$paper/cal-refined"

for robot in table-prpp positioner-2axis scara-rrpr; do
	plan=()
	[ -e "$robots/$robot-plan.toml" ] && plan=(--plan "$robots/$robot-plan.toml")
	run "simulate-$robot" simulate --robot "$robots/$robot.toml" --truth "$robots/$robot-truth.toml" \
		"${plan[@]}" --sim analytic --seed 3 --out "$out/$robot.csv"
	run "calibrate-$robot" calibrate "$out/$robot.csv" --robot "$robots/$robot.toml" --out "$out/cal-$robot"
done
run simulate-arm6 simulate --robot "$robots/arm6-dh.toml" --truth "$robots/arm6-dh-truth.toml" \
	--plan "$robots/arm6-jitter-plan.toml" --sim analytic --seed 3 --out "$out/arm6.csv"
run calibrate-arm6 calibrate "$out/arm6.csv" --robot "$robots/arm6-dh.toml" --out "$out/cal-arm6"

free=tests/data/independent-freepose
for data in clean backlash; do
	run "calibrate-kr-$data" calibrate "$free/$data.csv" --robot "$free/kr-arm.toml" --holdout \
		--out "$out/cal-kr-$data"
done
pg=tests/data/independent-parallelogram
for data in none balancer-f0.7; do
	run "calibrate-pg-$data" calibrate "$pg/$data.csv" --robot "$pg/pg-arm.toml" --out "$out/cal-pg-$data"
done

run blind-24 blind --cases 24 --seed 2 --sim analytic --out "$out/blind"

# Paths inside the outputs name the folder; the table names files relative to it.
cd "$out"
find . -type f ! -name '*.rrd' ! -name .axiscal.lock | LC_ALL=C sort | while read -r file; do
	sed "s#$out#OUT#g" "$file" | md5sum | sed "s#  -#  $file#"
done
