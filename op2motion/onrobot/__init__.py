"""What runs on the real OP2 through its bus (:mod:`op2motion.bus`, the transport): the applications, which plan and
check in physics before anything moves.

* :mod:`.plans` (moves from where the robot is, within the servos' speed, checked in physics);
* :mod:`.tasks` (what the ``op2motion robot`` commands do: status, read, setup, teach, limp, play);
* :mod:`.stand` (the feet closed and the walk-ready pose; a pose, a motion file or an action page played from where
  the robot is), :mod:`.walks` (a planned or steered walk, getting up; any controller started the checked way:
  :func:`.walks.run_on_robot`), :mod:`.teleop` (keys steering a walk);
* :mod:`.follow` (a target pose followed at a capped speed: the studio's);
* :mod:`.bench` (the loop's and the status's speed through the emulator).

Nothing here is imported at package import time: each module imports what it needs.
"""
