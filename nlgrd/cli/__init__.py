"""The ``nlgrd`` command line, thin over the library: the top layer, which nothing else in
nlgrd imports.

:mod:`.command` holds the parser and :func:`main` (the console script ``nlgrd``, and
``python -m nlgrd.cli``); each sub-command has its module: :mod:`.linear` (``modes``,
``campbell``, ``lste``), :mod:`.sweep` (``sweep``; :mod:`.link_sweep` and :mod:`.orbits`
for its models with links, ``--search-at`` and ``--period N``) and :mod:`.study`
(``study``, ``report``).
"""

from nlgrd.cli.command import build_parser, main

__all__ = ["build_parser", "main"]
