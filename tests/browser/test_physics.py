"""The page with the MuJoCo plant (--physics mujoco): the object placed
between the fingers is drawn as the part is, its shape and size from the
state's "object", green while held; gone with `object none`. Skipped when
the daemon was built without MuJoCo."""
import pytest
from selenium.webdriver.common.by import By

from conftest import wait
from wsgemu import DaemonError, Emulator

# The page's side view: 236 px span the 110 mm stroke (app.js).
PX = 236 / 110


@pytest.fixture
def emu(tmp_path):
    """A gripper with the MuJoCo plant, its control channel and page."""
    e = Emulator(args=["--web", "127.0.0.1:0", "--physics", "mujoco"])
    try:
        e.start()
    except DaemonError as err:
        if "without" in str(err):
            pytest.skip("wsgemu was built without MuJoCo")
        raise
    e.web = "http://" + e.fields["web"]
    yield e
    e.stop()


def drawn(driver):
    el = driver.find_element(By.ID, "object")
    return el if el.get_attribute("visibility") == "visible" else None


def size_of(el, attr):
    return float(el.get_attribute(attr))


def test_object_drawn_between_the_fingers(emu, page):
    assert emu.control.state()["object"] is None
    assert not drawn(page)
    emu.control.command("object box 40 20 30")
    el = wait(page).until(drawn)
    assert abs(size_of(el, "width") - 40 * PX) < 0.2
    assert abs(size_of(el, "height") - 30 * PX) < 0.2
    assert el.get_attribute("rx") == "0"
    # Centred between the fingers.
    assert abs(size_of(el, "x") + size_of(el, "width") / 2 - 160) < 1
    info = page.find_element(By.ID, "objectinfo")
    wait(page).until(lambda d: info.text.startswith("box 40 × 20 × 30 mm"))

    g = emu.gripper
    g.home()
    g.grasp(40.0, 50.0)
    wait(page).until(lambda d: "held" in drawn(d).get_attribute("class"))
    g.release(60.0, 50.0)

    emu.control.command("object sphere 25")
    wait(page).until(lambda d: drawn(d) and abs(
        size_of(drawn(d), "width") - 25 * PX) < 0.2)
    el = drawn(page)
    assert abs(size_of(el, "rx") - size_of(el, "width") / 2) < 0.1

    emu.control.command("object none")
    wait(page).until(lambda d: not drawn(d))
