/*
 * The Settings tab: the gripper's settings as GET /settings.json lists
 * them (each with its label, and for a number its unit and the model's
 * range), in a form built from that list, so a setting the server adds
 * shows up here without a change. "Apply" posts every field to
 * /settings.json and the daemon takes them at once; "Apply and save" adds
 * save=1, so they are written to the config file too. The server's
 * message (or its refusal, naming the setting and its range) shows under
 * the buttons.
 *
 * Element ids: settings-form, settings-<key> (settings-crc,
 * settings-acceleration, ...), settings-apply, settings-save,
 * settings-config, settings-message.
 */
'use strict';

(function () {
  const tab = document.getElementById('tab-settings');
  const el = wsg.el;
  /* The server checks every value with the command line's rules and says
   * what is wrong; the browser's own check (min, max) would only stop the
   * form without that message. */
  const form = el('form', { id: 'settings-form', noValidate: true });
  const fields = el('fieldset');
  const config = el('p', { id: 'settings-config' });
  const message = el('p', { id: 'settings-message', className: 'answer' });
  const apply = el('button', { type: 'submit', id: 'settings-apply',
    textContent: 'Apply' });
  const save = el('button', { type: 'button', id: 'settings-save',
    textContent: 'Apply and save' });
  let settings = [];

  message.setAttribute('aria-live', 'polite');
  fields.append(el('legend', { textContent: 'Gripper settings' }));
  form.append(fields, el('div', { className: 'actions' }, apply, save),
    message);
  tab.append(el('h2', { textContent: 'Settings' }), config, form);

  function input(s) {
    const id = 'settings-' + s.name;

    if (s.type === 'bool')
      return el('input', { type: 'checkbox', id, name: s.name,
        checked: s.value });
    if (s.type === 'number')
      return el('input', { type: 'number', id, name: s.name, step: 'any',
        min: s.min, max: s.max, value: s.value });
    return el('input', { type: 'text', id, name: s.name,
      value: s.value || '', placeholder: 'none' });
  }

  /* The form from the server's list, with its values. */
  function draw(answer) {
    settings = answer.settings || [];
    fields.replaceChildren(el('legend', { textContent: 'Gripper settings' }));
    settings.forEach((s) => {
      const unit = s.type === 'number'
        ? ' ' + s.unit + ' (' + s.min + '..' + s.max + ')' : '';

      fields.append(el('label', { htmlFor: 'settings-' + s.name },
        s.label + ' ', input(s), unit), el('br'));
    });
    config.textContent = answer.config
      ? 'Config file: ' + answer.config
      : 'No config file (--config): the settings can be applied, not saved.';
    save.disabled = !answer.config;
  }

  function values() {
    const out = {};

    settings.forEach((s) => {
      const e = document.getElementById('settings-' + s.name);

      out[s.name] = s.type === 'bool' ? (e.checked ? 'on' : 'off') : e.value;
    });
    return out;
  }

  function send(saving) {
    const f = values();

    if (saving)
      f.save = '1';
    message.textContent = '…';
    wsg.post('/settings.json', f).then((r) => {
      message.className = 'answer ' + (r.ok ? 'good' : 'bad');
      message.textContent = r.ok ? r.body.message : (r.body.error ||
        'failed (' + r.status + ')');
      if (r.ok)
        draw(r.body);
    });
  }

  form.addEventListener('submit', (e) => {
    e.preventDefault();
    send(false);
  });
  save.addEventListener('click', () => send(true));
  fetch('/settings.json').then((r) => r.json()).then(draw)
    .catch((e) => { message.textContent = String(e); });
})();
