"""The emulated OP2: the CM-730's and 20 MX-28's control tables, byte for byte, behind the wire's real timing
(:mod:`.timing`: 1 Mbps bytes, return delays, the FTDI's packets and latency timer), with a physics engine and the
servo model behind them (:class:`.server.Emulator`; the servos' tables side by side in :mod:`.bank`, so that the
body reads and fills all twenty at once), and faults to inject (:class:`.faults.Faults`); served on a
pseudo-terminal in real time, or in this process in lockstep (:mod:`.lockstep`, ``--port lockstep``).
``op2motion robot emulate --link PATH`` runs one on a pseudo-terminal; from Python::

    from op2motion.bus.emulator.server import Emulator
    emulator = Emulator(spec, engine="mujoco")
    emulator.open("/tmp/op2"); emulator.start()       # serve in a thread
    ...                                               # any program opens /tmp/op2 like /dev/ttyUSB0
    emulator.close()
"""
