"""Test-session set-up shared by every test module."""

import signal

# A shell without job control starts background jobs with SIGINT ignored, and Python then
# never installs its KeyboardInterrupt handler (nor do the processes it starts, which
# inherit the ignored disposition). The Ctrl-C tests need the interactive behaviour, so
# the session restores it; children exec'd from here start with SIGINT at its default.
signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_collection_modifyitems(config, items):
    """Notebook runs (papermill, minutes) count as slow: ``-m "not slow"`` is the inner loop."""
    import pytest

    for item in items:
        if item.get_closest_marker("notebook") is not None:
            item.add_marker(pytest.mark.slow)
