"""op2motion's own motions (``poses/motions/``): the get-up, roll and kick motions ship with the package as
``op2motion.motions`` (the other motions here are examples that refer to pose files beside them)."""
