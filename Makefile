# axiscal: the two commands a new user needs are `make run` and `make test`.
CARGO ?= cargo
OUT   ?= results/paper

.PHONY: run test bench study lint doc clean-results

## run: the paper scenario end to end; results under results/
run:
	$(CARGO) run --release -- simulate --seed 1 --out $(OUT)/campaign.csv --force
	$(CARGO) run --release -- evaluate --seed 1 --out $(OUT)

## test: the whole test suite (unit, integration, doc tests)
test:
	$(CARGO) test --all-targets
	$(CARGO) test --doc
	$(CARGO) run --quiet -- run scenarios/ci-smoke.toml --force --out results/ci-smoke

## study: the calibrator's efficiency against the Cramer-Rao bound (ML and the paper's
## estimator) and the calibration of its reported sigmas, 2000 simulated campaigns
study:
	$(CARGO) run --release -- study --trials 2000 --seed 1 --out results/study --force

## bench: criterion benchmarks (ratios against an in-run baseline)
bench:
	$(CARGO) bench

lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --all-targets -- -D warnings

doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps
