"""File formats: pose files, motion files, ROBOTIS action files (motion_4096.bin) and their layout, Webots motions and
CSV tables; each reader says what it expected and what it found."""
