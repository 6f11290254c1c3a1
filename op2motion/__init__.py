"""op2motion: whole-body motion generation for the ROBOTIS OP2 humanoid, checked in physics."""

__version__ = "0.1.0"
