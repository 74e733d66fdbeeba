"""The frame codec against the packets the manual and the project's README
show byte for byte, and the parser against the ways a stream arrives: in
pieces, with garbage, with a bad checksum. No daemon needed."""

import struct

import pytest

from wsgemu import Frame, FrameParser, Status, crc16, encode_frame, status_name
from wsgemu.client import _reply

# README "TCP": Homing, default direction.
HOMING = bytes.fromhex("AAAAAA20010000 8F83".replace(" ", ""))
# README "TCP": its answers, E_CMD_PENDING then E_SUCCESS.
HOMING_PENDING = bytes.fromhex("aaaaaa2002001a00fc32")
HOMING_SUCCESS = bytes.fromhex("aaaaaa200200 0000b3fd".replace(" ", ""))
# README "UDP": Get Opening Width and its answer, 55.0 mm.
GET_WIDTH = bytes.fromhex("AAAAAA430000BD54")
WIDTH_55 = bytes.fromhex("aaaaaa430600000000005c424e08")


def test_encode_matches_the_documented_packets():
    assert encode_frame(0x20, b"\x00") == HOMING
    assert encode_frame(0x43) == GET_WIDTH
    assert encode_frame(0x20, b"\x1a\x00") == HOMING_PENDING


def test_crc_over_a_whole_packet_is_zero():
    # The manual's Appendix C: a receiver may run the CRC over the packet
    # including its checksum and expect 0.
    for pkt in (HOMING, GET_WIDTH, HOMING_SUCCESS, WIDTH_55):
        assert crc16(pkt) == 0


def test_parser_decodes_replies_fed_byte_by_byte():
    p = FrameParser()
    frames = []
    for b in HOMING_PENDING + HOMING_SUCCESS + WIDTH_55:
        frames += p.feed(bytes([b]))
    replies = [_reply(f) for f in frames]
    assert [(r.cmd, r.status) for r in replies] == [
        (0x20, Status.E_CMD_PENDING), (0x20, Status.E_SUCCESS),
        (0x43, Status.E_SUCCESS)]
    assert struct.unpack("<f", replies[2].params)[0] == 55.0


def test_parser_skips_garbage_and_bad_checksums():
    bad = bytearray(WIDTH_55)
    bad[-1] ^= 0xFF
    p = FrameParser()
    frames = p.feed(b"\x00\xaa\x13" + bytes(bad) + b"\xaa\xaa" + HOMING)
    assert frames == [Frame(0x20, b"\x00")]
    assert p.bad_crc == 1


def test_parser_keeps_a_torn_preamble():
    p = FrameParser()
    assert p.feed(GET_WIDTH[:2]) == []
    assert p.feed(GET_WIDTH[2:]) == [Frame(0x43, b"")]


def test_encode_refuses_what_a_frame_cannot_carry():
    with pytest.raises(ValueError):
        encode_frame(0x100)
    with pytest.raises(ValueError):
        encode_frame(0x06, bytes(0x10000))


def test_status_names_follow_appendix_a():
    assert status_name(0) == "E_SUCCESS"
    assert status_name(3) == "E_NOT_INITIALIZED"
    assert status_name(26) == "E_CMD_PENDING"
    assert status_name(30) == "E_FILE_EXISTS"
    assert status_name(31) == "E_UNKNOWN"
