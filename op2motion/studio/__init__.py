"""The pose studio: a browser page to edit, balance and check a pose (``op2motion studio``)."""
