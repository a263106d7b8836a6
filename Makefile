# casflutter: the two quickstart commands (`make demo`, `make test`) set up .venv when missing.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-all bench clean

# single-threaded BLAS: the same seed gives the same numbers (threaded reductions reorder
# floating-point sums, and the nonconvex synthesis can end in another local optimum)
export OMP_NUM_THREADS = 1
export OPENBLAS_NUM_THREADS = 1
export MKL_NUM_THREADS = 1

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,slycot,dask]'
	touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(VENV)/bin/casflutter run

test: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest -m "not slow" -n 2 tests

test-all: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest -n 2 tests

bench: $(STAMP)
	$(VENV)/bin/casflutter bench identify --out bench-identify.json

clean:
	rm -rf build *.egg-info .pytest_cache casflutter-run
