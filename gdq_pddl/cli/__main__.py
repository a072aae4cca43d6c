"""``python -m gdq_pddl.cli``."""

from gdq_pddl.cli import main

raise SystemExit(main())
