"""The fingers on the web page (docs/fingers.md): the Diagnostics tab's
panel shows each finger's kind, power and force, and a DSA pad's cells as
a heat map that follows a grasp; the Settings tab fits the kinds as the
control channel does."""
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select

from conftest import text, wait

CELLS = 84


def cell(driver, finger, k):
    return int(driver.find_element(
        By.ID, "finger-%d-cell-%d" % (finger, k)).get_attribute("data-value"))


def cells(driver, finger):
    return [cell(driver, finger, k) for k in range(CELLS)]


def fit_on_page(page, kinds):
    """Fit the fingers through the Settings tab's form."""
    page.find_element(By.CSS_SELECTOR, "[data-tab=settings]").click()
    for i, kind in enumerate(kinds):
        Select(page.find_element(By.ID, "fingers-kind-%d" % i)) \
            .select_by_value(kind)
    page.find_element(By.ID, "fingers-apply").click()
    # The page clears the last fit's answer at once: two "ok" are this
    # fit's.
    wait(page).until(lambda d: text(d, "fingers-message").count("ok") == 2)


def test_settings_fit_the_kinds(emu, page):
    fit_on_page(page, ["dsa", "fmf"])
    fingers = emu.control.command("finger")
    assert '"kind":"dsa"' in fingers and '"kind":"fmf"' in fingers
    page.find_element(By.CSS_SELECTOR, "[data-tab=diagnostics]").click()
    wait(page).until(lambda d: text(d, "finger-0-kind") == "dsa")
    wait(page).until(lambda d: text(d, "finger-1-kind") == "fmf")
    assert text(page, "finger-0-power") == "on"
    # Only a DSA pad has a map.
    assert page.find_element(By.ID, "finger-0-map").is_displayed()
    assert not page.find_element(By.ID, "finger-1-map").is_displayed()
    fit_on_page(page, ["generic", "none"])
    assert '"kind":"none"' in emu.control.command("finger")


def test_heat_map_follows_a_grasp(emu, page):
    emu.control.command("finger 0 dsa")
    emu.control.command("finger 1 fmf")
    g = emu.gripper
    g.home()
    wait(page).until(lambda d: text(d, "finger-0-kind") == "dsa")
    # Nothing held: every cell 0.
    wait(page).until(lambda d: text(d, "finger-0-max") == "0")
    assert cells(page, 0) == [0] * CELLS
    emu.control.part(40.0)
    g.set_force_limit(20.0)
    g.grasp(40.0, 50.0)
    want = [int(x) for x in emu.control.command("finger 0 cells")[1:-1]
            .split(",")]
    assert max(want) > 0
    # The map shows the pad's frame as the control channel reads it, the
    # force the state's.
    wait(page).until(lambda d: cells(d, 0) == want)
    assert text(page, "finger-0-max") == str(max(want))
    wait(page).until(lambda d: float(text(d, "finger-0-force")) > 0)
    wait(page).until(lambda d: float(text(d, "finger-1-force")) > 0)
    # The patch lies in the middle of the pad: the cells there read, the
    # corners do not.
    assert cells(page, 0)[0] == 0 and cells(page, 0)[CELLS - 1] == 0
    # Let go: the map goes back to 0.
    g.release(60.0, 50.0)
    wait(page).until(lambda d: text(d, "finger-0-max") == "0")
    # Power off: the panel says so.
    emu.control.command("finger 0 power off")
    wait(page).until(lambda d: text(d, "finger-0-power") == "off")
