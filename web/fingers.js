/*
 * The fingers (docs/fingers.md): a panel in the Diagnostics tab with each
 * finger's kind, power and the force on its pad, and a DSA pad's cells as
 * a heat map (6 columns by 14 rows, row-major, 0..3895), and in the
 * Settings tab a choice of each finger's kind.
 *
 * Kind, power and force come with the state the page is pushed (its
 * "fingers"); the cells do not (84 numbers a finger would crowd the state),
 * so when a pushed state shows a DSA finger the page asks its control
 * channel for the frame (`finger I cells`), one request at a time, the
 * newest state winning: the map follows the state without a timer. The
 * kinds are set as the control channel sets them (`finger I KIND`,
 * `finger I device FILE`), at once, not saved.
 *
 * Element ids: fingers, finger-I-kind, finger-I-power, finger-I-force,
 * finger-I-map (its cells finger-I-cell-K), finger-I-max (the largest
 * cell), fingers-form, fingers-kind-I, fingers-model-I, fingers-apply,
 * fingers-message (I 0 or 1, K 0..83).
 */
'use strict';

(function () {
  const el = wsg.el;
  const COLS = 6;
  const ROWS = 14;
  const MAX = 3895;
  const KINDS = ['none', 'generic', 'fmf', 'dsa', 'device'];
  const diag = document.getElementById('tab-diagnostics');
  const settings = document.getElementById('tab-settings');
  const panel = el('section', { id: 'fingers', className: 'fingers' });
  const views = [0, 1].map((i) => {
    const map = el('div', { id: 'finger-' + i + '-map',
      className: 'dsa-map', hidden: true });
    const cells = [];

    map.setAttribute('role', 'img');
    map.setAttribute('aria-label', 'finger ' + i + ' pad, 6 by 14 cells');
    for (let k = 0; k < COLS * ROWS; k++) {
      const c = el('span', { id: 'finger-' + i + '-cell-' + k,
        className: 'dsa-cell' });
      c.dataset.value = '0';
      cells.push(c);
      map.append(c);
    }
    const v = {
      kind: el('span', { id: 'finger-' + i + '-kind', textContent: '–' }),
      power: el('span', { id: 'finger-' + i + '-power', textContent: '–' }),
      force: el('span', { id: 'finger-' + i + '-force', textContent: '–' }),
      max: el('span', { id: 'finger-' + i + '-max', textContent: '–' }),
      map,
      cells
    };
    panel.append(el('div', { className: 'finger-view' },
      el('h3', { textContent: 'Finger ' + i + (i ? ' (70h..73h)'
        : ' (60h..63h)') }),
      el('table', { className: 'readings' },
        el('tr', {}, el('th', { textContent: 'Kind' }), el('td', {}, v.kind)),
        el('tr', {}, el('th', { textContent: 'Power' }),
          el('td', {}, v.power)),
        el('tr', {}, el('th', { textContent: 'Force' }),
          el('td', {}, v.force, ' N')),
        el('tr', {}, el('th', { textContent: 'Largest cell' }),
          el('td', {}, v.max))),
      map));
    return v;
  });

  diag.append(el('h2', { textContent: 'Fingers' }), panel);

  /* ---- the heat map ---- */

  function paint(i, cells) {
    const v = views[i];
    let max = 0;

    cells.forEach((x, k) => {
      const c = v.cells[k];
      const t = Math.max(0, Math.min(1, x / MAX));

      if (!c)
        return;
      c.dataset.value = String(x);
      /* dark blue at 0 through red to yellow at the maximum */
      c.style.backgroundColor = 'hsl(' + Math.round(240 - 180 * t) +
        ',90%,' + Math.round(15 + 45 * t) + '%)';
      c.title = 'column ' + (k % COLS) + ', row ' +
        Math.floor(k / COLS) + ': ' + x;
      if (x > max)
        max = x;
    });
    v.max.textContent = String(max);
  }

  /* One `finger I cells` at a time; a state that comes meanwhile asks
   * again when it is answered. */
  const asking = [false, false];
  const again = [false, false];

  function fetchCells(i) {
    if (asking[i]) {
      again[i] = true;
      return;
    }
    asking[i] = true;
    wsg.post('/control', { line: 'finger ' + i + ' cells' }).then((a) => {
      const m = /^ok (\[.*\])/.exec((a.body && a.body.answer) || '');

      if (m) {
        try {
          paint(i, JSON.parse(m[1]));
        } catch (e) {
          /* not a frame: keep the last one */
        }
      }
      asking[i] = false;
      if (again[i]) {
        again[i] = false;
        fetchCells(i);
      }
    });
  }

  /* The state's fingers, and a frame asked for when the state changed. */
  const last = ['', ''];

  wsg.on('state', (s) => {
    (s.fingers || []).forEach((f, i) => {
      const v = views[i];
      const key = JSON.stringify(f) + s.width + s.grasp_state_name;

      if (!v)
        return;
      v.kind.textContent = f.kind + (f.fault ? ' (fault)' : '');
      v.power.textContent = f.powered ? 'on' : 'off';
      v.force.textContent = Number(f.force).toFixed(2);
      v.map.hidden = f.kind !== 'dsa';
      if (f.kind !== 'dsa') {
        v.max.textContent = '–';
        last[i] = '';
        return;
      }
      if (key !== last[i]) {
        last[i] = key;
        fetchCells(i);
      }
    });
  });

  /* ---- the kinds, in the Settings tab ---- */

  const form = el('form', { id: 'fingers-form', noValidate: true });
  const message = el('p', { id: 'fingers-message', className: 'answer' });
  const fields = el('fieldset', {},
    el('legend', { textContent: 'Fingers (at once, not saved)' }));
  const kinds = [0, 1].map((i) => {
    const sel = el('select', { id: 'fingers-kind-' + i });
    const model = el('input', { type: 'text', id: 'fingers-model-' + i,
      placeholder: 'device model file (device)' });

    KINDS.forEach((k) => sel.append(el('option', { value: k,
      textContent: k })));
    fields.append(el('label', { htmlFor: 'fingers-kind-' + i,
      textContent: 'Finger ' + i }), sel, model);
    return { sel, model };
  });

  message.setAttribute('aria-live', 'polite');
  form.append(fields, el('div', { className: 'actions' },
    el('button', { type: 'submit', id: 'fingers-apply',
      textContent: 'Fit' })), message);
  settings.append(el('h2', { textContent: 'Fingers' }), form);

  /* The form shows the kinds fitted until the user changes it. */
  let touched = false;
  form.addEventListener('input', () => { touched = true; });
  wsg.on('state', (s) => {
    if (touched)
      return;
    (s.fingers || []).forEach((f, i) => {
      if (kinds[i])
        kinds[i].sel.value = f.kind;
    });
  });

  form.addEventListener('submit', (ev) => {
    const lines = kinds.map((k, i) => 'finger ' + i + ' ' +
      (k.sel.value === 'device' ? 'device ' + k.model.value.trim()
        : k.sel.value));

    ev.preventDefault();
    /* The last answer goes at once: what shows next is this fit's. */
    message.textContent = 'Fitting...';
    message.classList.remove('bad');
    /* One after the other, as the control channel takes them. */
    lines.reduce((p, line) => p.then((out) =>
      wsg.post('/control', { line }).then((a) =>
        out.concat([{ ok: a.ok, text: a.body.answer || a.body.error }]))),
    Promise.resolve([])).then((out) => {
      message.textContent = out.map((o) => o.text).join('\n');
      message.classList.toggle('bad', out.some((o) => !o.ok));
      touched = false;
    });
  });
})();
