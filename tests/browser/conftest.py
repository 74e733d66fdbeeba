"""Fixtures of the browser tests: a daemon with its web page, a headless
Chromium driven through WebDriver, and the page opened and live.

The daemon is started by the project's Python package (wsgemu.Emulator);
the browser is Debian's Chromium with Debian's chromium-driver. Waits are
generous and scaled by WSG_TEST_TIME_SCALE: these machines are shared.
"""
import os
import pathlib
import urllib.parse
import urllib.request

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

from wsgemu import Emulator

SCALE = max(1.0, float(os.environ.get("WSG_TEST_TIME_SCALE", "1") or 1))
# The longest wait for something the page shows.
WAIT_S = 15.0 * SCALE
ARTIFACTS = pathlib.Path(os.environ.get("WSG_BROWSER_ARTIFACTS",
                                        "browser-artifacts"))


@pytest.fixture
def emu(tmp_path):
    """A gripper on TCP with the control channel and the web page, a
    script directory and a config file of its own."""
    scripts = tmp_path / "scripts"
    scripts.mkdir()
    config = tmp_path / "wsgemu.conf"
    config.write_text("# the browser tests' config\n")
    e = Emulator(args=["--web", "127.0.0.1:0", "--config", str(config),
                       "--script-dir", str(scripts)])
    e.scripts = scripts
    e.config = config
    e.start()
    e.web = "http://" + e.fields["web"]
    yield e
    e.stop()


@pytest.fixture(scope="session")
def browser():
    opts = webdriver.ChromeOptions()
    opts.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu",
                "--disable-dev-shm-usage", "--window-size=1280,1100"):
        opts.add_argument(arg)
    drv = webdriver.Chrome(service=Service("/usr/bin/chromedriver"),
                           options=opts)
    yield drv
    drv.quit()


@pytest.fixture
def page(emu, browser, request):
    """The page opened on emu's web server, its event stream live."""
    browser.get(emu.web + "/")
    wait(browser).until(lambda d: d.find_element(By.ID, "link").text == "live")
    yield browser
    # A failed test leaves a picture of what the page showed.
    rep = getattr(request.node, "rep_call", None)
    if rep is not None and rep.failed:
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        browser.save_screenshot(str(ARTIFACTS / (request.node.name + ".png")))


@pytest.hookimpl(tryfirst=True, hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    setattr(item, "rep_" + rep.when, rep)


def wait(driver, timeout=WAIT_S):
    return WebDriverWait(driver, timeout, poll_frequency=0.05)


def text(driver, element_id):
    """An element's text, shown or not (another tab's too)."""
    return driver.find_element(By.ID, element_id).get_attribute(
        "textContent").strip()


def post(url, fields):
    """A form POST as public clients send it; (status, body)."""
    data = urllib.parse.urlencode(fields).encode()
    req = urllib.request.Request(url, data=data, method="POST")
    try:
        with urllib.request.urlopen(req, timeout=WAIT_S) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as err:
        return err.code, err.read().decode()
