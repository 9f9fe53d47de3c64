# yade-qdem: `make demo` sets everything up and runs the default demo;
# `make test` builds and runs every test; `make doc` builds the site
# (out/doc/html/index.html).  See README.md.
SHELL   := /bin/bash
PY      := /usr/bin/python3.11
BUILD   := build
JOBS    ?= 2
# Where YADE's interpreter finds the package: system site for root, user site otherwise.
SITE    := $(shell if [ "$$(id -u)" = 0 ]; then echo /usr/local/lib/python3.11/dist-packages; \
             else $(PY) -c 'import site; print(site.getusersitepackages())' 2>/dev/null; fi)
YADE    := yade -n
export OMP_NUM_THREADS ?= 2

# YADE's Python modules (the path its launcher puts first), for tools run
# outside yade that import qdem's YADE parts: the documentation build.  Expanded
# when used, so that a fresh machine finds it after `make deps` installed YADE.
YADEPY   = $(shell sed -n "s/^sys\.path\.insert(1,'\(.*\)')$$/\1/p" $$(command -v yade 2>/dev/null) 2>/dev/null)

.PHONY: deps configure build ext install demo doc test test-all test-cpp test-py fuzz bench bench-mpi accuracy \
        compare-builds clean bench-tts

deps:
	@bash scripts/setup/deps.sh

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DQDEM_PYTHON=$(PY) > $(BUILD).cmake.log 2>&1 \
	  || (cat $(BUILD).cmake.log; exit 1)

# Everything: the extension, the C++ tests and the benchmarks.
build: configure
	@cmake --build $(BUILD) -j $(JOBS)

# The Python extension and package only: what the demo and the docs need.
ext: configure
	@cmake --build $(BUILD) -j $(JOBS) --target _core qdem_py

# The package with its subpackages; an older install is replaced, not
# overlaid (a module moved into a subpackage must not linger at its old path).
install: ext
	@test -n "$(SITE)" && rm -rf $(SITE)/qdem && mkdir -p $(SITE)/qdem
	@cd $(BUILD)/python/qdem && find . \( -name '*.py' -o -name '_core*.so' \) -not -path '*/__pycache__/*' \
	  -exec cp --parents {} $(SITE)/qdem/ \;
	@echo "qdem installed in $(SITE)/qdem"

demo: install
	@mkdir -p out/demo
	$(YADE) -x scripts/demo.py

# The site (Sphinx, MyST Markdown, furo): out/doc/html/index.html.  The API
# reference and the settings tables are generated from the package, so it
# needs the built extension; -W: any warning (a broken reference, a public
# name without a docstring, a stale settings table) fails.
doc: ext
	@mkdir -p out/doc
	@PYTHONPATH=$(CURDIR)/$(BUILD)/python:$(YADEPY) OMP_NUM_THREADS=1 $(PY) -m sphinx -b html -q -W --keep-going \
	  doc out/doc/html
	@echo "doc: out/doc/html/index.html"

# Everything, then one line: what passed and how long it took (logs in out/test/).
test:
	@mkdir -p out/test; rm -f out/test/cpp.log out/test/py.log; start=$$(date +%s); \
	$(MAKE) --no-print-directory test-all; rc=$$?; \
	t=$$(( $$(date +%s) - start )); \
	cpp=$$(grep -ho "[0-9]* tests failed out of [0-9]*" out/test/cpp.log 2>/dev/null | tail -1); \
	py=$$(grep -hoE "[0-9]+ (passed|failed)[^=]*" out/test/py.log 2>/dev/null | tail -1 | sed 's/ in [0-9.]*s.*//'); \
	echo "make test: $$([ $$rc = 0 ] && echo PASSED || echo FAILED) in $$((t / 60)) min $$((t % 60)) s;" \
	  "C++: $${cpp:-not run}; Python (docs included): $${py:-not run}"; exit $$rc

test-all: build test-cpp test-py

test-cpp:
	@mkdir -p out/test; set -o pipefail; cd $(BUILD) && ctest --output-on-failure -j $(JOBS) 2>&1 | tee $(CURDIR)/out/test/cpp.log

# The Python tests run inside YADE on PYTEST_WORKERS pytest-xdist workers (one
# per core, one OpenMP thread each: tests/python/conftest.py; the MPI tests
# all on one of them).  Here MPI is required: a build without it fails the MPI
# tests instead of skipping them (tests/python/mpi_launch.py).
PYTEST_WORKERS ?= 2
test-py:
	@mkdir -p out/test; set -o pipefail; \
	QDEM_TESTS_REQUIRE_MPI=1 PYTHONPATH=$(CURDIR)/$(BUILD)/python $(YADE) -x tests/python/run_pytest.py -q \
	  -n $(PYTEST_WORKERS) --dist loadgroup tests/python 2>&1 | tee out/test/py.log

# Random-scene fuzzer (doc/validation.md): batches of QDEM_FUZZ_BATCH fresh
# random examples until QDEM_FUZZ_SECONDS (default 600) have passed; the first
# failure stops it, shrunk and printed as a scene spec for
# tests/python/test_fuzz_regressions.py.  Hypothesis's database: out/fuzz/.
QDEM_FUZZ_SECONDS ?= 600
QDEM_FUZZ_BATCH ?= 30
fuzz: build
	@mkdir -p out/fuzz
	@end=$$(( $$(date +%s) + $(QDEM_FUZZ_SECONDS) )); n=0; \
	while [ $$(date +%s) -lt $$end ]; do \
	  n=$$((n + 1)); echo "fuzz: batch $$n of $(QDEM_FUZZ_BATCH) examples"; \
	  QDEM_FUZZ_LONG=1 QDEM_FUZZ_EXAMPLES=$(QDEM_FUZZ_BATCH) PYTHONPATH=$(CURDIR)/$(BUILD)/python \
	    $(YADE) -x tests/python/run_pytest.py -q -s -x tests/python/test_fuzz.py || exit 1; \
	done

bench: build
	@mkdir -p out/bench
	@PYTHONPATH=$(CURDIR)/$(BUILD)/python bash scripts/bench/run_all.sh

# The time-to-solution step of make bench alone (doc/performance.md, "Time to
# solution"): the shogi scenes at 766x and real size, each lever; 5-10 min.
bench-tts: build
	@mkdir -p out/bench
	@PYTHONPATH=$(CURDIR)/$(BUILD)/python OMP_WAIT_POLICY=passive $(PY) scripts/bench/bench_time_to_solution.py \
	  --out out/bench
	@$(PY) scripts/bench/perf_tables.py timeToSolution out/bench/time_to_solution.json

# MPI at scale (doc/parallel_scaling.md): ping-pong alpha/beta, the contact-free scene on 1-4
# ranks, the partitioner to 128 ranks, the weak-scaling model to 16,384;
# about 3-4 minutes.  Combined figures: out/bench/mpi.json, plots in out/bench/img
# (doc/parallel_scaling.md draws its own from the kept bench/logs/mpi.json).
MPIRUN := timeout 120 mpiexec --allow-run-as-root --oversubscribe
bench-mpi: build
	@mkdir -p out/bench
	@echo "bench-mpi: ping-pong, busy polling, then passive waits (as the oversubscribed runs)"
	@OMP_NUM_THREADS=1 $(MPIRUN) -n 2 $(PY) scripts/bench/mpi/pingpong.py --out out/bench/mpi_pingpong.json
	@OMP_NUM_THREADS=1 OMPI_MCA_mpi_yield_when_idle=1 $(MPIRUN) -n 2 $(PY) scripts/bench/mpi/pingpong.py \
	  --trials 5 --budget 0.02 --out out/bench/mpi_pingpong_yield.json
	@echo "bench-mpi: the partitioner alone, 1..128 ranks of 50,000 nodes"
	@OMP_NUM_THREADS=1 timeout 400 $(BUILD)/mpi_partition_model --out out/bench/mpi_partition.json > out/bench/mpi_partition.log
	@tail -1 out/bench/mpi_partition.log
	@echo "bench-mpi: the contact-free scene on 1..4 ranks"
	@$(PY) scripts/bench/mpi/run_ranks.py --build $(BUILD) --out out/bench/mpi_ranks.json
	@echo "bench-mpi: the weak-scaling model"
	@MPLBACKEND=Agg $(PY) scripts/bench/mpi/model.py --out out/bench/mpi_model.json --img out/bench/img \
	  --partition-more bench/logs/mpi_partition_512.json --combined out/bench/mpi.json

# What accuracy costs in time (3-5 min on one thread): out/accuracy/, doc/accuracy.md
accuracy: build
	@mkdir -p out/accuracy
	@OMP_NUM_THREADS=1 PYTHONPATH=$(CURDIR)/$(BUILD)/python $(PY) scripts/accuracy/implicit_viscosity.py --out out/accuracy
	@OMP_NUM_THREADS=1 PYTHONPATH=$(CURDIR)/$(BUILD)/python $(PY) scripts/accuracy/mass_scaling.py --out out/accuracy
	@OMP_NUM_THREADS=1 PYTHONPATH=$(CURDIR)/$(BUILD)/python $(PY) scripts/accuracy/run_accuracy.py --out out/accuracy

# Trajectories of this build against another one (OLD=<that build>/python):
# equal to rounding or it fails (doc/architecture.md); out/arch/compare.json.
compare-builds: build
	@test -n "$(OLD)" || (echo "make compare-builds OLD=<other build>/python"; exit 1)
	@OMP_WAIT_POLICY=passive $(PY) scripts/arch/compare_builds.py --old $(OLD) --new $(CURDIR)/$(BUILD)/python --out out/arch

clean:
	rm -rf $(BUILD) $(BUILD).cmake.log out
