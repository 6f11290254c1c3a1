"""What a WRITE of a span means for a control table, worked out once per span (a device is written the same span
every tick): refused outright, or the value range of each register it covers, and the registers it starts whose
writing the device reacts to. The rules (the CM-730 firmware's ``WriteControlTableRangeCheck``) are
:mod:`.devices`'s: a span beyond the table, one starting on the high byte of a word or ending on its low byte, a
read-only register, or (where the table refuses them) a byte of no register is a range error.
"""

from __future__ import annotations

from typing import NamedTuple

from op2motion.bus.tables import ControlTable, Register


class WritePlan(NamedTuple):
    """A WRITE's plan: ``refused`` whatever the values; else ``checks`` (offset in the data, end, lowest, highest)
    per register covered, and ``reactions`` (name, address, end) of the registers it starts that the device reacts
    to."""

    refused: bool
    checks: tuple[tuple[int, int, int, int], ...]
    reactions: tuple[tuple[str, int, int], ...]


REFUSED = WritePlan(True, (), ())


def write_plan(table: ControlTable, reacts_to: frozenset[str], address: int, length: int) -> WritePlan:
    """The plan of a WRITE of ``length`` bytes at ``address`` to a device of ``table`` that reacts to the registers
    named in ``reacts_to``."""
    end = address + length
    if not length or end > table.size:
        return REFUSED
    covers: list[Register | None] = [None] * table.size              # the register holding each byte
    for register in table.registers:
        covers[register.address:register.end] = [register] * register.size
    checks, reactions = [], []
    a = address
    while a < end:
        r = covers[a]
        if r is None:
            if not table.gaps_writable:
                return REFUSED
            a += 1
            continue
        if r.address < address or r.end > end or r.access != "RW":   # half a word, or read-only
            return REFUSED
        checks.append((r.address - address, r.end - address, *table.limits_of(r)))
        if r.name in reacts_to:
            reactions.append((r.name, r.address, r.end))
        a = r.end
    return WritePlan(False, tuple(checks), tuple(reactions))
