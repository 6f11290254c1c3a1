"""Instruction packets out of the host's byte stream as the CM-730 firmware takes them (``ProcessPackets`` of
``CM_DXL_COM.c``): header, ID, length, then that many bytes; a packet whose checksum does not match comes out
marked, for the device it names to answer with the checksum error (:mod:`.wire`).
"""

from __future__ import annotations

from op2motion.bus import protocol as p

HEAD_BYTES = 4                     # FF FF ID LEN
MIN_LENGTH = 2                     # LEN counts the instruction and the checksum


class FirmwareParser:
    """Instruction packets out of the byte stream as a device's firmware reads them (``ProcessPackets``): after a
    header (further FF before the ID are skipped) the ID, the length and that many bytes make one packet; each comes
    out with whether its checksum matches. ``discarded`` counts bytes outside packets, ``bad_checksums`` the packets
    whose checksum did not match."""

    def __init__(self) -> None:
        self.buffer = bytearray()
        self.discarded = 0
        self.bad_checksums = 0

    def feed(self, data: bytes | bytearray) -> list[tuple[p.Packet, bool]]:
        """Add ``data``; every complete packet now in the buffer, in order, with whether its checksum matches."""
        buf = self.buffer
        buf += data
        out: list[tuple[p.Packet, bool]] = []
        while True:
            start = buf.find(p.HEADER)
            if start < 0:
                keep = 1 if buf[-1:] == b"\xff" else 0            # a lone FF may start the next header
                self.discarded += len(buf) - keep
                del buf[:len(buf) - keep]
                return out
            self.discarded += start
            del buf[:start]
            if len(buf) < HEAD_BYTES:
                return out
            if buf[2] == 0xFF:                                     # FF FF FF: the header starts one byte later
                self.discarded += 1
                del buf[:1]
                continue
            if buf[3] < MIN_LENGTH:
                self.discarded += 2
                del buf[:2]
                continue
            end = HEAD_BYTES + buf[3]
            if len(buf) < end:
                return out
            body = bytes(buf[2:end - 1])
            intact = p.checksum(body) == buf[end - 1]
            if not intact:
                self.bad_checksums += 1
            out.append((p.Packet(body[0], body[2], body[3:]), intact))
            del buf[:end]

    def clear(self) -> None:
        """Forget what is buffered."""
        self.buffer.clear()
