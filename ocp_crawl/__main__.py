"""``python -m ocp_crawl``: the ``ocp-crawl`` command line."""
from .cli import main

raise SystemExit(main())
