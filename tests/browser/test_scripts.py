"""Scripting from the page, in a real browser (issue: the gripper's web
page): a script uploaded and started from the page answers its
registered command ID over TCP, its print shows in the console, Stop ends
it, and a failing script shows its error and D20."""
import struct

from selenium.webdriver.common.by import By

from conftest import text, wait

ECHO = """-- Answers command B7h with its own payload and a count, as a research
-- stack's script does with the IDs it registers.
cmd.register(0xB7)
print("echo ready")
local n = 0
while true do
  local id, payload = cmd.read()
  n = n + 1
  cmd.send(id, etob(E_SUCCESS), payload, n)
end
"""

FAILING = """print("about to fail")
error("the part is not where it should be")
"""


def open_scripting(page):
    page.find_element(By.CSS_SELECTOR,
                      '.tabs button[data-tab="scripting"]').click()
    wait(page).until(lambda d: "Directory" in text(d, "scripts-dir"))


def upload(page, path):
    page.find_element(By.ID, "scripts-upload-file").send_keys(str(path))
    page.find_element(By.ID, "scripts-upload").click()
    wait(page).until(lambda d: d.find_elements(
        By.CSS_SELECTOR, '#scripts-list tr[data-name="%s"]' % path.name))


def run_from_list(page, name):
    page.find_element(
        By.CSS_SELECTOR,
        '#scripts-list tr[data-name="%s"] button[data-action="run"]'
        % name).click()


def test_uploaded_script_answers_its_id_over_tcp(emu, page, tmp_path):
    src = tmp_path / "echo.lua"
    src.write_text(ECHO)
    open_scripting(page)
    upload(page, src)
    # Uploaded into the script directory, byte for byte.
    assert (emu.scripts / "echo.lua").read_text() == ECHO
    run_from_list(page, "echo.lua")
    wait(page).until(lambda d: text(d, "script-state").startswith("running"))
    wait(page).until(lambda d: "echo ready" in text(d, "script-console"))
    # The script's own command, over the gripper's TCP interface.
    reply = emu.gripper.request(0xB7, b"\x01\x02")
    assert reply.status_name == "E_SUCCESS"
    assert reply.params[:2] == b"\x01\x02"
    page.find_element(By.ID, "script-stop").click()
    wait(page).until(lambda d: text(d, "script-state").startswith("stopped"))
    assert not emu.control.script_status()["running"]


def test_failing_script_shows_its_error_and_d20(emu, page, tmp_path):
    (emu.scripts / "fail.lua").write_text(FAILING)
    open_scripting(page)
    page.find_element(By.ID, "scripts-refresh").click()
    wait(page).until(lambda d: d.find_elements(
        By.CSS_SELECTOR, '#scripts-list tr[data-name="fail.lua"]'))
    run_from_list(page, "fail.lua")
    wait(page).until(lambda d: "not where it should be" in text(
        d, "script-error"))
    assert "set" in page.find_element(
        By.ID, "script-failure").get_attribute("class")
    assert "set" in page.find_element(
        By.ID, "flag-script_failure").get_attribute("class")
    assert "about to fail" in text(page, "script-console")
