"""``python -m nlgrd.cli``: the ``nlgrd`` command."""

from nlgrd.cli.command import main

raise SystemExit(main())
