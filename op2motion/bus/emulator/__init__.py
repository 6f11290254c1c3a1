"""The emulated OP2: the CM-730's and 20 MX-28's control tables on a pseudo-terminal, byte for byte, with a physics
engine and the servo model behind them in real time (:class:`.server.Emulator`), and faults to inject
(:class:`.faults.Faults`). ``op2motion robot emulate --link PATH`` runs one; from Python::

    from op2motion.bus.emulator.server import Emulator
    emulator = Emulator(spec, engine="mujoco")
    emulator.open("/tmp/op2"); emulator.start()       # serve in a thread
    ...                                               # any program opens /tmp/op2 like /dev/ttyUSB0
    emulator.close()
"""
