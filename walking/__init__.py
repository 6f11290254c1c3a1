"""Gait presets (``walking/NAME.toml``), shipped with op2motion as package data ``op2motion.walking``."""
