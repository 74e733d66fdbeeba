/*
 * The Scripting tab: the script directory as a file manager (list,
 * upload, download, edit, delete: /scripts.json and /scripts/NAME), an
 * editor, Run and Stop (/script/run, /script/stop), and a console that
 * shows what the script prints as it prints it.
 *
 * The console needs no polling: a script's print is a "script print TEXT"
 * line of the communication log, which the server pushes anyway; the
 * script's name, whether it runs (D19) and its error (D20) are in every
 * pushed state ("script" and "flags"). The file list is fetched when the
 * tab is built and after each change made from here: files changed by
 * hand in the directory show after Refresh.
 *
 * Element IDs are stable (the docs and browser tests name them); the
 * list's rows carry data-name and their buttons data-action.
 */
'use strict';

(function () {
  const UPLOAD_MAX = 256 * 1024; /* the server's cap on a script */
  const CONSOLE_LINES = 2000; /* the console keeps the newest */
  const SF_SCRIPT_RUNNING = 1 << 19; /* D19 */
  const SF_SCRIPT_FAILURE = 1 << 20; /* D20 */
  const PRINT = ' script print ';

  const el = wsg.el;
  const tab = document.getElementById('tab-scripting');
  let running = false; /* the newest state's D19 */

  /* ---- the panel ---- */
  const dir = el('p', { id: 'scripts-dir', className: 'answer' });
  const list = el('tbody', { id: 'scripts-list' });
  const refresh = el('button', { type: 'button', id: 'scripts-refresh',
    textContent: 'Refresh' });
  const uploadFile = el('input', { type: 'file', id: 'scripts-upload-file',
    accept: '.lua', multiple: true });
  const upload = el('button', { type: 'button', id: 'scripts-upload',
    textContent: 'Upload' });
  const answer = el('p', { id: 'scripts-answer', className: 'answer' });
  answer.setAttribute('aria-live', 'polite');

  const name = el('input', { type: 'text', id: 'script-name',
    placeholder: 'name.lua', autocomplete: 'off', spellcheck: false });
  const editor = el('textarea', { id: 'script-editor', rows: 18,
    spellcheck: false, className: 'editor',
    placeholder: '-- a script: e.g.\ncmd.register(0xB0)\nwhile true do\n' +
      '  local id, p = cmd.read()\n  cmd.send(id, etob(E_SUCCESS), p)\nend' });
  const save = el('button', { type: 'button', id: 'script-save',
    textContent: 'Save' });
  const saveRun = el('button', { type: 'button', id: 'script-save-run',
    textContent: 'Save and run' });
  const run = el('button', { type: 'button', id: 'script-run',
    textContent: 'Run' });
  const stop = el('button', { type: 'button', id: 'script-stop',
    textContent: 'Stop' });

  const state = el('span', { id: 'script-state', textContent: '–' });
  const failure = el('span', { id: 'script-failure', className: 'indicator',
    textContent: 'D20' });
  failure.title = 'SF_SCRIPT_FAILURE: the last script ended with an error';
  const error = el('pre', { id: 'script-error', className: 'answer bad' });
  const consoleView = el('pre', { id: 'script-console',
    className: 'log console' });
  consoleView.setAttribute('aria-live', 'off');
  const consoleClear = el('button', { type: 'button',
    id: 'script-console-clear', textContent: 'Clear' });

  const head = el('tr', {}, el('th', { textContent: 'Name' }),
    el('th', { textContent: 'Size' }), el('th', { textContent: 'Modified' }),
    el('th'));
  tab.append(
    el('h2', { textContent: 'Scripts' }), dir,
    el('table', { className: 'files' }, el('thead', {}, head), list),
    el('div', { className: 'logbar' }, refresh, uploadFile, upload),
    answer,
    el('h2', { textContent: 'Editor' }),
    el('div', { className: 'logbar' },
      el('label', {}, 'name ', name), save, saveRun),
    editor,
    el('h2', { textContent: 'Script' }),
    el('div', { className: 'logbar' }, run, stop,
      el('span', {}, 'state: ', state), failure),
    error,
    el('h2', { textContent: 'Console' }),
    el('div', { className: 'logbar' }, consoleClear),
    consoleView);

  function say(text, bad) {
    answer.textContent = text;
    answer.className = bad ? 'answer bad' : 'answer';
  }

  /* A request's answer as {ok, status, body}: body is the JSON (or
   * {error: text} for an answer that is not JSON, e.g. a 413 of MHD's). */
  function call(method, path, body) {
    return fetch(path, { method, body })
      .then((r) => r.text().then((t) => {
        let j;
        try {
          j = JSON.parse(t);
        } catch (e) {
          j = { error: t || r.statusText };
        }
        return { ok: r.ok, status: r.status, body: j };
      }))
      .catch((e) => ({ ok: false, status: 0, body: { error: String(e) } }));
  }

  const fileUrl = (n) => '/scripts/' + encodeURIComponent(n);

  /* ---- the file list ---- */
  function row(f) {
    const tr = el('tr');
    tr.dataset.name = f.name;
    const cells = [
      el('td', { textContent: f.name }),
      el('td', { textContent: String(f.size) }),
      el('td', { textContent: new Date(f.mtime * 1000).toLocaleString() })
    ];
    const actions = el('td');
    [['run', 'Run'], ['download', 'Download'], ['edit', 'Edit'],
      ['delete', 'Delete']].forEach(([action, text]) => {
      const button = el('button', { type: 'button', textContent: text });
      button.dataset.action = action;
      actions.append(button);
    });
    tr.append(...cells, actions);
    return tr;
  }

  function load() {
    return call('GET', '/scripts.json').then((a) => {
      list.textContent = '';
      if (!a.ok) {
        dir.textContent = a.body.error || ('error ' + a.status);
        dir.className = 'answer bad';
        return;
      }
      dir.textContent = 'Directory ' + a.body.dir + ': ' +
        a.body.scripts.length + ' script' +
        (a.body.scripts.length === 1 ? '' : 's') +
        (a.body.more ? ' (and ' + a.body.more + ' more not listed)' : '');
      dir.className = 'answer';
      a.body.scripts.forEach((f) => list.append(row(f)));
    });
  }

  function runScript(n) {
    if (!n)
      return Promise.resolve(say('No script named: type a name.', true));
    return wsg.post('/script/run', { name: n }).then((a) => {
      if (a.ok)
        say('Running ' + n + '.');
      else
        say(n + ': ' + (a.body.error || 'error ' + a.status), true);
      return a;
    });
  }

  function edit(n) {
    return fetch(fileUrl(n))
      .then((r) => (r.ok ? r.text() : Promise.reject(r.status)))
      .then((t) => {
        name.value = n;
        editor.value = t;
        say('Editing ' + n + '.');
      })
      .catch((s) => say(n + ': not loaded (' + s + ')', true));
  }

  list.addEventListener('click', (ev) => {
    const button = ev.target.closest('button[data-action]');
    if (!button)
      return;
    const n = button.closest('tr').dataset.name;
    switch (button.dataset.action) {
    case 'run':
      runScript(n);
      break;
    case 'download': {
      /* The server answers with Content-Disposition: attachment. */
      const a = el('a', { href: fileUrl(n), download: n });
      document.body.append(a);
      a.click();
      a.remove();
      break;
    }
    case 'edit':
      edit(n);
      break;
    case 'delete':
      if (!window.confirm('Delete ' + n + '?'))
        return;
      call('DELETE', fileUrl(n)).then((a) => {
        say(a.ok ? 'Deleted ' + n + '.' : n + ': ' + a.body.error, !a.ok);
        load();
      });
      break;
    }
  });

  refresh.addEventListener('click', load);

  /* One file after the other, each by its own name. */
  upload.addEventListener('click', () => {
    const files = Array.from(uploadFile.files || []);
    if (!files.length)
      return say('Choose a .lua file first.', true);
    const done = [];
    return files.reduce((p, f) => p.then(() => {
      if (f.size > UPLOAD_MAX) {
        done.push(f.name + ': larger than 256 KiB');
        return null;
      }
      return call('PUT', fileUrl(f.name), f).then((a) => done.push(
        f.name + ': ' + (a.ok ? (a.status === 201 ? 'uploaded' : 'replaced')
          : a.body.error)));
    }), Promise.resolve()).then(() => {
      say(done.join('\n'), done.some((t) => !/(uploaded|replaced)$/.test(t)));
      uploadFile.value = '';
      load();
    });
  });

  /* ---- the editor ---- */
  function saveEditor() {
    const n = name.value.trim();
    if (!n) {
      say('Name the script first: name.lua', true);
      return Promise.resolve(false);
    }
    return call('PUT', fileUrl(n), editor.value).then((a) => {
      say(a.ok ? 'Saved ' + n + '.' : n + ': ' + a.body.error, !a.ok);
      load();
      return a.ok;
    });
  }

  save.addEventListener('click', saveEditor);
  /* Saving and running is how a script is tried out: a script that runs
   * is stopped first, as only one runs at a time. */
  saveRun.addEventListener('click', () => saveEditor().then((ok) => {
    if (!ok)
      return null;
    return (running ? wsg.post('/script/stop') : Promise.resolve())
      .then(() => runScript(name.value.trim()));
  }));
  run.addEventListener('click', () => runScript(name.value.trim()));
  stop.addEventListener('click', () => wsg.post('/script/stop').then((a) =>
    say(a.body.stopped ? 'Stopped.' : 'No script was running.')));

  /* ---- the state and the console ---- */
  wsg.on('state', (s) => {
    const sc = s.script || {};
    running = (s.flags & SF_SCRIPT_RUNNING) !== 0;
    state.textContent = (running ? 'running' : 'stopped') +
      (sc.name ? ' (' + sc.name + ')' : '');
    state.className = running ? 'running' : '';
    failure.className = 'indicator' +
      ((s.flags & SF_SCRIPT_FAILURE) !== 0 ? ' set' : '');
    error.textContent = sc.error || '';
    stop.disabled = !running;
  });

  let consoleLines = [];
  wsg.on('log', (lines) => {
    const printed = [];
    lines.forEach((l) => {
      const at = l.indexOf(PRINT);
      if (at >= 0)
        printed.push(l.slice(at + PRINT.length));
    });
    if (!printed.length)
      return;
    consoleLines = consoleLines.concat(printed);
    if (consoleLines.length > CONSOLE_LINES)
      consoleLines = consoleLines.slice(consoleLines.length - CONSOLE_LINES);
    consoleView.textContent = consoleLines.join('\n');
    consoleView.scrollTop = consoleView.scrollHeight;
  });
  consoleClear.addEventListener('click', () => {
    consoleLines = [];
    consoleView.textContent = '';
  });

  load();
})();
