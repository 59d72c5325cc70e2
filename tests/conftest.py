"""Test-session set-up shared by every test module."""

import signal

# A shell without job control starts background jobs with SIGINT ignored, and Python then
# never installs its KeyboardInterrupt handler (nor do the processes it starts, which
# inherit the ignored disposition). The Ctrl-C tests need the interactive behaviour, so
# the session restores it; children exec'd from here start with SIGINT at its default.
signal.signal(signal.SIGINT, signal.default_int_handler)


#: The longest test files, run first: with ``make test``'s workers (pytest-xdist, one file
#: per worker at a time, in collection order) they start at once and the short files fill
#: in after them, instead of two long files ending the run on their own.
FIRST = (
    "test_notebooks",
    "test_design_study",
    "test_two_stage_time_domain",
    "test_geared_time_domain",
    "test_geared_clearance_time_domain",
    "test_reports",
    "test_geared_time_domain_regimes",
    "test_link_time_domain",
    "test_link_modal",
    "test_outputs",
    "test_jeffcott_jumps",
    "test_studies",
)


def pytest_collection_modifyitems(config, items):
    """Notebook runs (papermill, minutes) count as slow: ``-m "not slow"`` is the inner loop.
    The files of :data:`FIRST` go first (a stable sort: the order within a file is kept)."""
    import pytest

    for item in items:
        if item.get_closest_marker("notebook") is not None:
            item.add_marker(pytest.mark.slow)
    rank = {name: i for i, name in enumerate(FIRST)}
    items.sort(key=lambda item: rank.get(item.module.__name__.rpartition(".")[2], len(FIRST)))
