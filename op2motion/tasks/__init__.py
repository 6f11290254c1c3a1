"""User tasks, one function each, every one returning a :class:`~.result.TaskResult` (``ok``, ``problem``,
``warnings``, the outputs to write, ``as_dict()``): the command line parses, calls one task, prints and writes.

* :mod:`.motion`: ``play_page_task``, ``plan_motion_task``, ``line_move_task`` (an action page, a motion through
  poses, a hand in a straight line), each checked along its trajectory and optionally in physics (``check_motion``);
* :mod:`.posture`: ``reach`` (``optimize``: a balanced pose that reaches a hand target);
* :mod:`.walk`: ``walk_task`` (a walk planned from a preset, checked in physics, pushed, on the family);
* :mod:`.steered`: ``steered_walk_task`` (a walk steered by a command timeline, checked and drawn);
* :mod:`.kinematics`: ``fk``, ``convert``, ``plot``, ``arm_ik`` (the kinematic models, the figure, the arm IK);
* :mod:`.files`: ``export_poses``, ``import_page``, ``list_pages``, ``export_motion``, ``urdf`` (action files,
  Webots, CSV, the URDF);
* :mod:`.library`: ``build`` (a grid of reach targets solved on workers);
* :mod:`.bench`: ``bench`` (the speed figures, each with a check of the timed work);
* :mod:`.robot`: ``robot_status``, ``robot_setup``, ``robot_read``, ``robot_play``, ``robot_walk``,
  ``robot_steered_walk``, ``robot_stand``, ``robot_getup``, ``emulated`` (the real OP2 on its bus, the
  emulated one's report);
* :mod:`.tune`: ``tune`` (an Optuna study of a walk or the stock module's config, verified, written);
* :mod:`.validate`: ``validate_pose``, ``validate_pose_robust`` (does a pose stand, in one engine or both, pushed, on
  the robustness family).
"""
