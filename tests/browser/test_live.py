"""The live view, STOP and ACK, the scenario panel and the log, in a real
browser (issue: the gripper's web page)."""
import pytest
from selenium.webdriver.common.by import By

from conftest import ARTIFACTS, WAIT_S, text, wait
from wsgemu import SystemFlag, WsgError


def width_shown(driver):
    return float(text(driver, "width"))


def test_width_follows_a_move(emu, page):
    g = emu.gripper
    g.home()
    wait(page).until(lambda d: width_shown(d) == 110.0)
    emu.control.time_scale(0.2)  # 10 mm take 2 s: the page sees it move
    start = width_shown(page)
    pending = g.move(60.0, 25.0, wait=False)
    seen = set()

    def moving(d):
        seen.add(width_shown(d))
        return len(seen) >= 4
    # Several widths on the way: the view is live, not a final value.
    wait(page).until(moving)
    assert all(60.0 <= w <= start for w in seen)
    pending.wait(WAIT_S)
    wait(page).until(lambda d: width_shown(d) == 60.0)
    emu.control.time_scale(1)


def test_stop_stops_a_move(emu, page):
    g = emu.gripper
    g.home()
    emu.control.time_scale(0.1)
    pending = g.move(10.0, 20.0, wait=False)
    wait(page).until(lambda d: "set" in d.find_element(
        By.ID, "flag-moving").get_attribute("class"))
    page.find_element(By.ID, "stop").click()
    wait(page).until(lambda d: text(d, "result") == "STOP: E_SUCCESS")
    with pytest.raises(WsgError) as err:
        pending.wait(WAIT_S)
    assert err.value.status_name == "E_CMD_ABORTED"
    flags = g.system_state()
    assert flags & SystemFlag.SF_AXIS_STOPPED
    assert not flags & SystemFlag.SF_MOVING
    stopped_at = g.width()
    assert 10.0 < stopped_at < 110.0
    wait(page).until(lambda d: "set" not in d.find_element(
        By.ID, "flag-moving").get_attribute("class"))
    emu.control.time_scale(1)


def test_ack_clears_a_fast_stop(emu, page):
    g = emu.gripper
    g.fast_stop()
    flag = page.find_element(By.ID, "flag-fast_stop")
    wait(page).until(lambda d: "set" in flag.get_attribute("class"))
    assert g.system_state() & SystemFlag.SF_FAST_STOP
    page.find_element(By.ID, "ack").click()
    wait(page).until(lambda d: "set" not in flag.get_attribute("class"))
    assert not g.system_state() & SystemFlag.SF_FAST_STOP


def test_scenario_panel_places_a_part(emu, page):
    part = page.find_element(By.ID, "part-width")
    part.clear()
    part.send_keys("42.5")
    page.find_element(By.ID, "part-place").click()
    wait(page).until(lambda d: "ok part 42.5" in text(d, "scenario-answer"))
    assert emu.control.state()["part"]["width"] == 42.5
    wait(page).until(lambda d: text(d, "partinfo").startswith("42.5 mm"))
    page.find_element(By.ID, "part-remove").click()
    wait(page).until(lambda d: text(d, "partinfo") == "none")
    line = page.find_element(By.ID, "control-line")
    line.send_keys("bogus")
    page.find_element(By.ID, "control-send").click()
    wait(page).until(lambda d: "error unknown command" in text(
        d, "scenario-answer"))


def test_log_shows_packets(emu, page):
    emu.gripper.width()
    wait(page).until(lambda d: "out 43h GetOpeningWidth E_SUCCESS" in text(
        d, "log"))


def test_screenshot(emu, page):
    """The picture for the README and the test's artifacts: a gripper
    holding a part, its log, after a grasp."""
    g = emu.gripper
    g.home()
    emu.control.part(40.0)
    g.grasp(40.0, 50.0)
    wait(page).until(lambda d: text(d, "grasp") == "Holding")
    # Tall enough for the log; the plot has drawn the grasp by then.
    size = page.get_window_size()
    page.set_window_size(1280, 1400)
    try:
        wait(page).until(lambda d: "out 25h Grasp E_SUCCESS" in text(d, "log"))
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        assert page.save_screenshot(str(ARTIFACTS / "web-page.png"))
    finally:
        page.set_window_size(size["width"], size["height"])
