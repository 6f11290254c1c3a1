"""The robot: its spec (joints, links, masses, servos; read from specs/*.toml), poses and supports, the servo
tables and the ROBOTIS framework's own constants, the IMU's mapping. The bottom layer: imports nothing above it."""
