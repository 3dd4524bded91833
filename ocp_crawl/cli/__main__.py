from ocp_crawl.cli.app import main

raise SystemExit(main())
