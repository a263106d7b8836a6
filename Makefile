# casflutter: the two quickstart commands (`make demo`, `make test`) set up .venv when missing.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-all bench clean docs wheel

# single-threaded BLAS: the same seed gives the same numbers (threaded reductions reorder
# floating-point sums, and the nonconvex synthesis can end in another local optimum)
export OMP_NUM_THREADS = 1
export OPENBLAS_NUM_THREADS = 1
export MKL_NUM_THREADS = 1

$(STAMP): pyproject.toml constraints.txt
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c constraints.txt -e '.[test,slycot,dask]'
	touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(VENV)/bin/casflutter run --overwrite

test: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest -m "not slow" -n 2 tests

test-all: $(STAMP)
	MPLBACKEND=Agg $(PY) -m pytest -n 2 tests

# the documentation site (docs/_build/html): warnings are errors; the gallery examples run at
# a small size (CASFLUTTER_DOCS_QUICK=1)
DOCS_STAMP := $(VENV)/.docs-installed

$(DOCS_STAMP): pyproject.toml constraints.txt $(STAMP)
	$(PY) -m pip install --quiet -c constraints.txt -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	CASFLUTTER_DOCS_QUICK=1 MPLBACKEND=Agg $(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

# the wheel (LICENSE, py.typed and the problem definitions inside) in dist/
wheel: $(STAMP)
	$(PY) -m pip wheel --no-deps --quiet -w dist .

bench: $(STAMP)
	$(VENV)/bin/casflutter bench identify --out bench-identify.json

clean:
	rm -rf build dist *.egg-info .pytest_cache casflutter-run docs/_build docs/auto_examples docs/generated docs/sg_execution_times.rst
