# axiscal: the two commands a new user needs are `make run` and `make test`.
CARGO ?= cargo
OUT   ?= results/paper
VENV  ?= .venv
# The rerun viewer must match the `rerun` crate pinned in Cargo.toml.
RERUN_VERSION := $(shell sed -n 's/^rerun = { version = "=\([0-9.]*\)".*/\1/p' Cargo.toml)

FUZZ_SECONDS ?= 600
# One optimised build for every target here: the `quick-release` profile with the rerun
# recorder (feature `viz`), so that `make run`, `make test` and the rest build it once.
QUICK := --profile quick-release --features viz
# The binary the integration tests run: that build. The tests themselves are built in the same
# profile with the same features, so they link the libraries that build compiled (a debug build
# would compile every dependency again and run the calibrations about 10 times slower).
TEST_BIN ?= $$(cd $${CARGO_TARGET_DIR:-target} && pwd)/quick-release/axiscal

.PHONY: run test test-real test-robots noise-check iso9283-check certificate tool-accuracy bench fuzz study blind blind-free-poses blind-analytic budget lint doc clean-results setup-viewer view

## run: the paper scenario end to end; results under results/ (with a rerun recording:
## `make view`). Built with the rerun recorder (feature `viz`) in the `quick-release` profile.
run:
	$(CARGO) run $(QUICK) -- simulate --seed 1 --out $(OUT)/campaign.csv --record $(OUT)/campaign.rrd --force
	$(CARGO) run $(QUICK) -- evaluate --seed 1 --floor-seeds 30 --force --out $(OUT)
	$(CARGO) run $(QUICK) -- budget --seeds 30 --force --out results/budget
	$(CARGO) run $(QUICK) -- run scenarios/paper.toml --force --out $(OUT)/montecarlo

## setup-viewer: the matching rerun viewer (`rerun` binary) in a local virtual environment
setup-viewer:
	test -x $(VENV)/bin/python || python3 -m venv $(VENV)
	$(VENV)/bin/pip install --disable-pip-version-check rerun-sdk==$(RERUN_VERSION)

## view: open the recording of `make run` (prints the install command if no viewer is found)
view:
	$(CARGO) run $(QUICK) -- view $(OUT)/campaign.rrd

## test: the whole test suite (unit, integration, doc tests; the benchmarks are `make bench`'s);
## reads nothing outside the repository. Built as `make run` builds (the `quick-release` profile
## with the recorder): the integration tests (the recorder's included) and the smoke scenario
## run that binary (TEST_BIN). A plain `cargo test` runs the same tests in the debug build,
## and there also the refusal of `--record` by a build without the recorder.
test:
	$(CARGO) build $(QUICK)
	AXISCAL_TEST_BIN="$(TEST_BIN)" $(CARGO) test $(QUICK) --lib --bins --tests --examples
	$(CARGO) test $(QUICK) --doc
	$(TEST_BIN) run scenarios/ci-smoke.toml --force --out results/ci-smoke

## test-real: the tests on public real data sets, which need ../shared/data/real/ beside the
## repository (or AXISCAL_SHARED_DIR naming the shared folder); the commands they run are the
## optimised build's (TEST_BIN, as `make test`)
test-real:
	$(CARGO) build $(QUICK)
	AXISCAL_TEST_BIN="$(TEST_BIN)" $(CARGO) test $(QUICK) --test it -- --ignored real_boby_klimchik:: real_fanuc:: real_sscanss2:: real_rct:: hostile_calibration:: hostile_round6a:: hostile_round9a:: hostile_round9c:: hostile_round9e:: hostile_round10a:: hostile_round10c:: hostile_round10d:: hostile_round11a:: hostile_round11e:: hostile_round13a:: hostile_round14a:: hostile_round14e:: hostile_round15a:: hostile_round16m:: hostile_round18m::a_swap

## test-robots: the four issue-15 test robots (P-R-P-P table, two-axis positioner, SCARA,
## six-axis arm with a repeated sweep and wandering held joints), 50 seeds of noise each:
## normalised RMS error of every identified parameter and the count beyond 3 sigma
test-robots:
	$(CARGO) test --release --test it -- --ignored test_robots:: --nocapture

## iso9283-check: ISO 9283 tests after calibration, 200 simulated (paper robot, theodolites),
## measured against their Monte-Carlo prediction: mean measured / predicted AP and RP within 10 %
iso9283-check:
	$(CARGO) run $(QUICK) -- run scenarios/iso9283.toml --force --out results/iso9283

## certificate: the calibration certificate of the simulated paper campaign (seed 1), as
## results/certificate/certificate.html and .json, rendered to certificate.png by headless
## Chromium (Debian's package, installed when missing)
certificate:
	$(CARGO) run $(QUICK) -- simulate --seed 1 --out results/certificate/campaign.csv --force
	$(CARGO) run $(QUICK) -- calibrate results/certificate/campaign.csv --out results/certificate/cal --force
	$(CARGO) run $(QUICK) -- report --calibration results/certificate/cal/calibration.json \
		--data results/certificate/campaign.csv --held-out results/certificate/campaign.csv \
		--instrument "two theodolites (simulated), 0.19 mm net radial error" --out results/certificate --force
	scripts/render-html.sh results/certificate/certificate.html results/certificate/certificate.png

## noise-check: the noise estimated from the residuals on 200 Table-1 campaigns (within 10 %,
## interval coverage >= 90 %)
noise-check:
	$(CARGO) test --release --test it -- --ignored noise_and_held:: --nocapture

## tool-accuracy: the predicted tool 1-sigma against a Monte-Carlo of 2000 calibrations of the
## paper robot, inside the calibrated spans and over the workspace (within 10 %)
tool-accuracy:
	$(CARGO) test --release --test it -- --ignored tool_accuracy:: --nocapture

## study: the calibrator's efficiency against the Cramer-Rao bound (ML and the paper's
## estimator) and the calibration of its reported sigmas, 20000 simulated campaigns
study:
	$(CARGO) run --release -- study --trials 20000 --seed 1 --out results/study --force

## fuzz: mutants of valid files against every reader (measurement CSV, descriptions, scenarios,
## effects, calibration.json) for FUZZ_SECONDS seconds (default 600); a failure is written to
## target/fuzz-failures/
fuzz:
	FUZZ_SECONDS=$(FUZZ_SECONDS) $(CARGO) test --release --test it -- --ignored fuzz_readers:: --nocapture

## bench: criterion benchmarks (ratios against an in-run baseline)
bench:
	$(CARGO) bench

lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --all-targets -- -D warnings
	$(CARGO) clippy --all-targets --features viz -- -D warnings

doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps

## budget: the paper's gap budget (per unmodelled effect, the magnitude that raises the
## simulated calibrated error to the paper's 1.40 mm), 30 campaigns per magnitude
budget:
	$(CARGO) run --release -- budget --seeds 30 --force --out results/budget

## blind: blind check of `axiscal diagnose` on 162 shape-varying cases on the rapier arm (hidden
## keys; about 1 min on 2 cores), confusion matrix and per-member table under results/blind/summary.md
blind:
	$(CARGO) run --release -- blind --cases 162 --seed 2 --sim rapier --out results/blind --force

## blind-free-poses: the blind check with free poses only (the six-axis arm6-dh, 300 poses a
## case, no axis experiment; about 5 min on 2 cores), results/blind-free-poses/summary.md
blind-free-poses:
	$(CARGO) run --release -- blind --cases 162 --seed 2 --campaign free-poses --out results/blind-free-poses --force

## blind-analytic: the same 162 cases on the analytic arm (first-order compliance, 7 CPU-min),
## results/blind-analytic/summary.md
blind-analytic:
	$(CARGO) run --release -- blind --cases 162 --seed 2 --out results/blind-analytic --force
