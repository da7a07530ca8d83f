"""``python -m rosfpga_lab`` is the same as the ``rosfpga-lab`` command."""

from rosfpga_lab.cli import main

raise SystemExit(main())
