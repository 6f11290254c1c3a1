"""The OP2's limbs as groups of joints, by the joints' official names (the spec's): ``head``, ``arms``, ``left_arm``,
``right_arm``, ``legs``, ``left_leg``, ``right_leg`` and ``all``, as the Action Editor lets a limb go limp on its own
(``op2motion robot read --limp left_arm,head``).

A joint belongs to a limb by its name: ``head_*`` the head; ``l_``/``r_`` then a shoulder or elbow joint
(:data:`ARM_JOINTS`) an arm, then a hip, knee or ankle joint (:data:`~op2motion.robot.joints.LEG_JOINTS`) a leg.
"""

from __future__ import annotations

from typing import Sequence

from op2motion.errors import InputError
from op2motion.robot.joints import LEG_JOINTS

#: The joints of one arm from the shoulder out, by official name without the side's ``l_``/``r_`` prefix.
ARM_JOINTS = ("sho_pitch", "sho_roll", "el")
HEAD_PREFIX = "head_"
SIDE_PREFIXES = {"left": "l_", "right": "r_"}
#: Groups named before their parts, so a description names the largest limb a selection holds whole.
GROUPS = ("all", "legs", "arms", "head", "left_leg", "right_leg", "left_arm", "right_arm")


def limb_groups(joint_names: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """Each group of :data:`GROUPS`: its joints among ``joint_names``, in their order."""
    def limb(prefix: str, parts: tuple[str, ...]) -> tuple[str, ...]:
        return tuple(n for n in joint_names if n.startswith(prefix) and n[len(prefix):] in parts)

    sides = {f"{side}_{kind}": limb(prefix, parts) for side, prefix in SIDE_PREFIXES.items()
             for kind, parts in (("arm", ARM_JOINTS), ("leg", LEG_JOINTS))}
    both = {kind: tuple(n for n in joint_names if n in sides[f"left_{kind[:-1]}"] + sides[f"right_{kind[:-1]}"])
            for kind in ("arms", "legs")}
    head = tuple(n for n in joint_names if n.startswith(HEAD_PREFIX))
    groups = {"all": tuple(joint_names), "head": head, **both, **sides}
    return {g: groups[g] for g in GROUPS}


def select_joints(text: str, joint_names: Sequence[str], param: str = "limp") -> tuple[str, ...]:
    """The joints ``text`` names (comma-separated groups of :data:`GROUPS` and joint names, e.g.
    ``left_arm,head`` or ``r_knee``), once each, in ``joint_names``' order; anything else is bad input (``param``)."""
    groups = limb_groups(joint_names)
    items = [item.strip() for item in str(text).split(",")]
    chosen: set[str] = set()
    for item in items:
        if item in groups:
            chosen.update(groups[item])
        elif item in joint_names:
            chosen.add(item)
        else:
            raise InputError(f"expected comma-separated limbs ({', '.join(GROUPS)}) or joint names "
                             f"({', '.join(joint_names)}), got {item!r}", param)
    return tuple(n for n in joint_names if n in chosen)


def describe_joints(joints: Sequence[str], joint_names: Sequence[str]) -> str:
    """``joints`` for people: the whole limbs they hold by group name, then any other joint by its name, and the
    count (``left_arm, head (5 joints)``, ``all (20 joints)``)."""
    left, named = [n for n in joint_names if n in joints], []
    for group, members in limb_groups(joint_names).items():
        if members and set(members) <= set(left):
            named.append(group)
            left = [n for n in left if n not in members]
    count = len(set(joints))
    return f"{', '.join(named + left)} ({count} joint{'s' if count != 1 else ''})"
