"""``python -m leadthrough.cli``: the command-line tool."""

from leadthrough.cli.main import main

raise SystemExit(main())
