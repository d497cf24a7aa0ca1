"""``python -m flexdigit.cli``: the ``flexdigit`` command."""

from flexdigit.cli import main

raise SystemExit(main())
