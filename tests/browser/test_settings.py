"""Settings, the Motion tab and the form endpoints, in a real browser
(issue: the gripper's web page): a setting changes behaviour on the wire,
the page moves the gripper, and the forms public code posts move and
configure it."""
import json
import socket
import struct
import time
import urllib.request

from selenium.webdriver.common.by import By

from conftest import WAIT_S, post, text, wait
from wsgemu import FrameParser, Status


def crc16(data):
    """CRC-16 CCITT as the manual's packets use it (initial 0xFFFF)."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021 if crc & 0x8000 else crc << 1) & 0xFFFF
    return crc


def ask_with_bad_crc(addr, cmd):
    """cmd (no payload) over a new TCP connection with a wrong checksum:
    the answer's status and parameters."""
    head = bytes([0xAA, 0xAA, 0xAA, cmd]) + struct.pack("<H", 0)
    bad = (crc16(head) ^ 0x5A5A) & 0xFFFF
    with socket.create_connection(addr, timeout=WAIT_S) as s:
        s.sendall(head + struct.pack("<H", bad))
        parser = FrameParser()
        while True:
            data = s.recv(256)
            assert data, "the connection closed without an answer"
            frames = parser.feed(data)
            if frames:
                assert frames[0].cmd == cmd
                status, = struct.unpack("<H", frames[0].payload[:2])
                return status, frames[0].payload[2:]


def open_tab(page, name):
    page.find_element(By.CSS_SELECTOR,
                      '.tabs button[data-tab="%s"]' % name).click()


def test_crc_setting_changes_the_wire(emu, page):
    # With the check on (the default), a wrong checksum is refused.
    assert ask_with_bad_crc(emu.tcp_addr, 0x43) == (Status.E_CHECKSUM_ERROR,
                                                     b"")
    open_tab(page, "settings")
    box = page.find_element(By.ID, "settings-crc")
    wait(page).until(lambda d: box.is_displayed())
    assert box.is_selected()
    box.click()
    page.find_element(By.ID, "settings-save").click()
    wait(page).until(lambda d: "saved" in text(d, "settings-message").lower()
                     or "applied" in text(d, "settings-message").lower())
    # Off: the same packet is served, at once and on the wire.
    status, params = ask_with_bad_crc(emu.tcp_addr, 0x43)
    assert status == Status.E_SUCCESS and len(params) == 4
    # Saved: the config file says so, for the next start.
    conf = emu.config.read_text()
    assert any(line.replace(" ", "") in ("crc=off", "no-crc=on")
               for line in conf.splitlines()), conf


def test_bad_setting_is_refused_with_a_message(emu, page):
    before = emu.gripper.get_acceleration()
    open_tab(page, "settings")
    acc = page.find_element(By.ID, "settings-acceleration")
    wait(page).until(lambda d: acc.is_displayed())
    acc.clear()
    acc.send_keys("99999")
    page.find_element(By.ID, "settings-apply").click()
    wait(page).until(lambda d: "acceleration" in text(d, "settings-message"))
    assert "range" in text(page, "settings-message")
    # Nothing changed on the wire.
    assert emu.gripper.get_acceleration() == before


def test_motion_tab_moves_the_gripper(emu, page):
    open_tab(page, "motion")
    page.find_element(By.ID, "motion-home").click()
    wait(page).until(lambda d: "E_" in text(d, "motion-answer"))
    wait(page).until(lambda d: float(text(d, "width")) == 110.0)
    width = page.find_element(By.ID, "motion-width")
    width.clear()
    width.send_keys("42")
    page.find_element(By.ID, "motion-move").click()
    wait(page).until(lambda d: float(text(d, "width")) == 42.0)
    assert abs(emu.gripper.width() - 42.0) < 0.01


def test_form_endpoints_move_and_configure(emu):
    g = emu.gripper
    g.home()
    # The motion form as a public client posts it: a move (sender 1221).
    status, body = post(emu.web + "/motion.json", {
        "1207": "30", "1214": "80", "1247": "20", "1254": "50",
        "1261": "40", "1291": "5", "1298": "80", "1334": "1000",
        "1341": "3", "1348": "2", "sender_id": "1221", "event_type": "0"})
    # A motion started: its answer is the one the wire gives (21h pending).
    assert status == 202, body
    assert json.loads(body)["status"] == "E_CMD_PENDING"

    deadline = time.monotonic() + WAIT_S
    while abs(g.width() - 30.0) > 0.01 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert abs(g.width() - 30.0) < 0.01
    # The grasping configuration as Xamla's client posts it.
    status, body = post(emu.web + "/graspconf.json", {
        "253": "4.5", "260": "2.5", "sender_id": "342", "event_type": "0"})
    assert status == 200, body
    with urllib.request.urlopen(emu.web + "/settings.json",
                                timeout=WAIT_S) as r:
        settings = json.loads(r.read())
    values = {s["name"]: s["value"] for s in settings["settings"]}
    assert values["width-tolerance"] == 4.5
    assert values["clamping-travel"] == 2.5
