"""Test-session set-up shared by every test module."""

import signal

# Both BLAS libraries (numpy's and scipy's own OpenBLAS) loaded now, at their default
# thread count, so that :func:`one_blas_thread` limits both and a test that asks for two
# threads (threadpool_limits(2), tests/test_machine_independence.py) gets them.
import numpy  # noqa: F401
import pytest
import scipy.linalg  # noqa: F401
from threadpoolctl import threadpool_limits

# A shell without job control starts background jobs with SIGINT ignored, and Python then
# never installs its KeyboardInterrupt handler (nor do the processes it starts, which
# inherit the ignored disposition). The Ctrl-C tests need the interactive behaviour, so
# the session restores it; children exec'd from here start with SIGINT at its default.
signal.signal(signal.SIGINT, signal.default_int_handler)


#: The longest test files, longest first (each alone, one BLAS thread, 2026-12-04: 163 s
#: down to about 20 s): with ``make test``'s workers (pytest-xdist, one file per
#: worker at a time, in collection order) they start at once and the short files fill in
#: after them, instead of a long file ending the run on its own.
FIRST = (
    "test_notebooks",
    "test_design_study",
    "test_period_doubling_fe",
    "test_folds",
    "test_reports",
    "test_two_stage_time_domain",
    "test_period_doubling",
    "test_studies",
    "test_geared_clearance_time_domain",
    "test_beyond_period_one",
    "test_runout_unbalance",
    "test_harmonic_convergence",
    "test_link_time_domain",
    "test_jeffcott_jumps",
    "test_parametric_mesh",
    "test_parametric_mesh_fe",
    "test_shaft_orders",
    "test_geared_time_domain",
    "test_orbit_search",
    "test_moved_verdicts",
)

#: Modules that keep the default BLAS threads (see :func:`one_blas_thread`):
#: tests/test_studies.py compares the serial executor, run in this process, with Dask
#: workers byte for byte, relying on each task running with one BLAS thread in every
#: executor (nlgrd.studies.study_tasks.run_task sets it); with this process at one thread
#: already, a task that lost its own limit would go unnoticed there.
KEEP_BLAS_THREADS = frozenset({"test_studies"})
#: What the processes a test starts (the CLI, notebook kernels, Dask workers) read at start.
BLAS_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread(request):
    """One BLAS thread in each test module, here and in the processes its tests start.

    ``make test`` runs a worker per core, so the cores are taken; a BLAS call that starts
    more threads then waits for cores the other worker holds, and OpenBLAS's threads spin
    while they wait. On the 2-core machine the suite is timed on (2026-12-04, each file
    alone, back to back): tests/test_pole_residue.py 16-105 s with the default two threads,
    depending on what else ran, and 5 s with one; tests/test_notebooks.py 403 s and 163 s;
    tests/test_cli.py 55 s and 9 s. Sweeps, continuations and time integrations already run
    with one thread (nlgrd.threads), so this changes the speed of the rest, not what is
    computed: results differ by rounding at most, which tests/test_machine_independence.py
    bounds (it sets one and two threads itself, threadpool_limits inside this limit, and
    gets both)."""
    if request.module.__name__.rpartition(".")[2] in KEEP_BLAS_THREADS:
        yield
        return
    with threadpool_limits(limits=1, user_api="blas"), pytest.MonkeyPatch.context() as mp:
        for name in BLAS_ENV:
            mp.setenv(name, "1")
        yield


def pytest_collection_modifyitems(config, items):
    """Notebook runs (papermill, minutes) count as slow: ``-m "not slow"`` is the inner loop.
    The files of :data:`FIRST` go first (a stable sort: the order within a file is kept)."""
    for item in items:
        if item.get_closest_marker("notebook") is not None:
            item.add_marker(pytest.mark.slow)
    rank = {name: i for i, name in enumerate(FIRST)}
    items.sort(key=lambda item: rank.get(item.module.__name__.rpartition(".")[2], len(FIRST)))
