# axiscal: the two commands a new user needs are `make run` and `make test`.
CARGO ?= cargo
OUT   ?= results/paper

.PHONY: run test bench lint doc clean-results

## run: the paper scenario end to end; results under results/
run:
	$(CARGO) run --release -- simulate --seed 1 --out $(OUT)/campaign.csv --force
	$(CARGO) run --release -- evaluate --seed 1 --out $(OUT)

## test: the whole test suite (unit, integration, doc tests)
test:
	$(CARGO) test --all-targets
	$(CARGO) test --doc

## bench: criterion benchmarks (ratios against an in-run baseline)
bench:
	$(CARGO) bench

lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --all-targets -- -D warnings

doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps
