"""``python -m ocp_crawl``: the ``ocp-crawl`` command line."""
from ocp_crawl.cli.app import main

raise SystemExit(main())
