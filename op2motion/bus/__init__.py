"""The real OP2 on its own bus, the transport: Dynamixel Protocol 1.0 to the CM-730 and the 20 MX-28, the framework's
8 ms loop, safety, and an emulated OP2 to develop without a robot. It imports nothing of the physics, the gait, the
motions or the postures but the emulator (the robot's own PC needs numpy and pyserial only); what runs on the robot
through it (moves checked in physics, the walks, the ``op2motion robot`` commands) is :mod:`op2motion.onrobot`.

Layers inside the wing, lowest first:

* :mod:`.protocol` (packets, checksums, instructions, error bits by name) and :mod:`.tables` (the MX-28's and the
  CM-730's control tables as data);
* :mod:`.clock` (the one clock the bus keeps its time by: the wall, or an emulated OP2's lockstep time);
* :mod:`.port` (a serial port opened safely: only a tty, held exclusively, 1 Mbps, the USB adapter's latency timer
  set to 1 ms and read back, bounded timeouts), :mod:`.link` (what a transaction costs: byte times, return delays,
  the adapter's tail as measured; the tick's read plan; the refusal of a link too slow for the loop) and
  :mod:`.client` (ping, read, write, sync write, bulk read with bounded waits and retries; late replies dropped and
  counted);
* :mod:`op2motion.robot.imu` (below the wing, shared with the stock gait's emulation: the board's register words
  <-> the torso's gyro [rad/s] and accelerometer [m/s²], by the spec's ``[imu]`` mapping), :mod:`.robot` (the OP2
  on the bus: power, status, torque, gains, present state),
  :mod:`.safety` (the named policy and thresholds);
* :mod:`.session` (the port, the board found, the servos powered, the whole robot read, the torque on without a
  jump);
* :mod:`.loop` (:func:`.loop.run_controller`: any physics :class:`~op2motion.physics.Controller` on the robot, one
  bulk read and one sync write every 8 ms, at real-time priority where allowed: :mod:`.realtime`; how a run ends:
  :mod:`.stopping`);
* :mod:`.emulator` (the emulated OP2: the control tables byte for byte, the wire's time, physics and the servo model
  behind them; on a pseudo-terminal in real time, or in this process in lockstep).

Nothing here is imported at package import time: each module imports what it needs.
"""
