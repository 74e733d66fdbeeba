/*
 * The web page's life: what the gripper is (/info.json) once, then its
 * state and its communication log as the server pushes them (/events: a
 * "state" event whenever the state changes, "log" events with new log
 * lines, none while nothing happens), drawn as they come. Nothing here
 * polls or runs on a timer, so a page left open on an idle gripper costs
 * nothing.
 *
 * This file runs the sidebar (flags, grasping state, STOP and ACK), the
 * tabs and the Diagnostics tab. The other tabs' scripts (settings.js,
 * scripts.js, motion.js) build their own panel and use window.wsg:
 *   wsg.on('state' | 'log' | 'info', fn)  fn(state) / fn(lines) / fn(info)
 *   wsg.state, wsg.info                   the newest of each (or null)
 *   wsg.post(path, fields)                a form POST: {ok, status, body}
 *   wsg.el(tag, props, ...children)       a DOM element
 */
'use strict';

window.wsg = (function () {
  const handlers = { state: [], log: [], info: [] };
  const api = {
    state: null,
    info: null,
    on(type, fn) {
      handlers[type].push(fn);
      /* A late subscriber gets what is known already. */
      if (type === 'state' && api.state)
        fn(api.state);
      if (type === 'info' && api.info)
        fn(api.info);
    },
    emit(type, value) {
      handlers[type].forEach((fn) => fn(value));
    },
    /* fields: an object or URLSearchParams, sent url-encoded (the forms
     * the real gripper's page posts). The answer's JSON in body. */
    post(path, fields) {
      const body = new URLSearchParams(fields || {});
      return fetch(path, { method: 'POST', body })
        .then((r) => r.json().catch(() => ({})).then((j) => ({
          ok: r.ok, status: r.status, body: j })))
        .catch((e) => ({ ok: false, status: 0,
          body: { error: String(e) } }));
    },
    el(tag, props, ...children) {
      const e = document.createElement(tag);
      Object.assign(e, props || {});
      children.forEach((c) => e.append(c));
      return e;
    }
  };
  return api;
})();

(function () {
  const WINDOW_MS = 10000; /* the plot's span */
  const LOG_LINES = 1000; /* the log view keeps the newest */
  /* Flags that mean something is wrong: drawn red when set. */
  const ALARMS = new Set(['fast_stop', 'temp_warning', 'temp_fault',
    'power_fault', 'curr_fault', 'finger_fault', 'cmd_failure',
    'script_failure']);
  const GRASP_NAMES = {
    idle: 'Idle', grasping: 'Grasping', no_part: 'No part found',
    part_lost: 'Part lost', holding: 'Holding', releasing: 'Releasing',
    positioning: 'Positioning', error: 'Error'
  };

  const $ = (id) => document.getElementById(id);
  let info = null; /* /info.json */
  let last = null; /* the newest state */
  const history = []; /* {t, width, force}, oldest first */

  function fixed(v, digits) {
    return typeof v === 'number' ? v.toFixed(digits) : '–';
  }

  /* One list item per named flag, in bit order (D0 first). */
  function buildFlags() {
    const ul = $('flags');
    ul.textContent = '';
    info.flag_names.forEach((name, bit) => {
      if (!name)
        return;
      const li = document.createElement('li');
      const b = document.createElement('span');
      li.id = 'flag-' + name;
      li.dataset.bit = String(bit);
      b.className = 'bit';
      b.textContent = 'D' + bit;
      li.appendChild(b);
      li.appendChild(document.createTextNode(name.toUpperCase()));
      if (ALARMS.has(name))
        li.classList.add('alarm');
      ul.appendChild(li);
    });
  }

  function showFlags(s) {
    for (const li of $('flags').children) {
      const bit = Number(li.dataset.bit);
      li.classList.toggle('set', ((s.flags >>> bit) & 1) === 1);
    }
  }

  /* The fingers close symmetrically about the middle; the stroke spans
   * the rail. */
  function showGripper(s) {
    const stroke = info ? info.stroke : 110;
    const mid = 160, span = 236, fw = 22;
    const px = span / stroke;
    const half = Math.max(0, Math.min(s.width, stroke)) * px / 2;
    $('finger-l').setAttribute('x', (mid - half - fw).toFixed(1));
    $('finger-r').setAttribute('x', (mid + half).toFixed(1));
    const part = $('part');
    if (s.part) {
      const w = Math.max(1, s.part.width * px);
      part.setAttribute('x', (mid - w / 2).toFixed(1));
      part.setAttribute('width', w.toFixed(1));
      part.setAttribute('visibility', 'visible');
      part.classList.toggle('held', s.grasp_state_name === 'holding');
    } else {
      part.setAttribute('visibility', 'hidden');
    }
    /* An obstacle blocks both fingers at its width: drawn at each. */
    const ob = $('obstacle');
    if (typeof s.obstacle === 'number') {
      const half = Math.max(0, Math.min(s.obstacle, stroke)) * px / 2;
      ob.setAttribute('x', (mid - half - 2).toFixed(1));
      ob.setAttribute('width', (2 * half + 4).toFixed(1));
      ob.setAttribute('visibility', 'visible');
    } else {
      ob.setAttribute('visibility', 'hidden');
    }
  }

  /* A physics plant's object (--physics mujoco), in the same side view:
   * x across the fingers from the middle, z up the scene, the fingers'
   * tips up on the page as the scene's hang down, so the pads' middle
   * (z = -23.8 mm in the model's scene) is the drawn fingers' middle. A
   * box shows its width and height, a cylinder (its axis along the
   * fingers) its diameter and length, a sphere a circle. */
  function showObject(s) {
    const el = $('object');
    const row = $('objectrow');
    const o = s.object;
    if (!el || !row)
      return;
    row.hidden = o === undefined || o === null;
    if (!o || !o.pos) {
      el.setAttribute('visibility', 'hidden');
      if (!o && $('objectinfo'))
        $('objectinfo').textContent = 'none';
      return;
    }
    const stroke = info ? info.stroke : 110;
    const mid = 160, span = 236, bottom = 130;
    const px = span / stroke;
    const w = Math.max(1, o.size[0] * px);
    const h = Math.max(1, (o.kind === 'box' ? o.size[2]
      : o.kind === 'cylinder' ? o.size[1] : o.size[0]) * px);
    const cx = mid + o.pos[0] * px, cy = bottom + o.pos[2] * px;
    el.setAttribute('x', (cx - w / 2).toFixed(1));
    el.setAttribute('y', (cy - h / 2).toFixed(1));
    el.setAttribute('width', w.toFixed(1));
    el.setAttribute('height', h.toFixed(1));
    el.setAttribute('rx', o.kind === 'sphere' ? (w / 2).toFixed(1) : '0');
    el.dataset.kind = o.kind;
    /* Out of the view (fallen away): not drawn. */
    el.setAttribute('visibility', cy + h / 2 < 0 || cy - h / 2 > 170
      ? 'hidden' : 'visible');
    el.classList.toggle('held', s.grasp_state_name === 'holding');
    $('objectinfo').textContent = o.kind + ' ' +
      o.size.slice(0, o.kind === 'box' ? 3 : o.kind === 'cylinder' ? 2 : 1)
        .join(' × ') + ' mm, ' + o.mass + ' kg';
  }

  function showReadings(s) {
    $('width').textContent = fixed(s.width, 1);
    $('speed').textContent = fixed(s.speed, 1);
    $('force').textContent = fixed(s.force, 1);
    $('temperature').textContent = fixed(s.temperature, 1);
    $('partinfo').textContent = s.part
      ? s.part.width.toFixed(1) + ' mm, ' + s.part.stiffness + ' N/mm'
      : 'none';
    $('stats').textContent = s.stats.total + ' total, ' + s.stats.no_part +
      ' no part, ' + s.stats.lost_part + ' lost';
    $('time').textContent = s.time.toFixed(3) + ' s' +
      (s.paused ? ' (paused)' : s.scale !== 1 ? ' (×' + s.scale + ')' : '');
    $('grasp').textContent = GRASP_NAMES[s.grasp_state_name] ||
      s.grasp_state_name;
  }

  /* Width on the left scale (0..stroke), force on the right (0..the
   * overdrive force), over the last WINDOW_MS ending now. */
  function drawPlot() {
    const c = $('plot');
    const ctx = c.getContext('2d');
    const w = c.width, h = c.height, pad = 6;
    const now = performance.now();
    const wmax = info ? info.stroke : 110;
    const fmax = info ? info.overdrive_force : 120;

    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = '#e3e6ea';
    ctx.lineWidth = 1;
    for (let i = 1; i < 4; i++) {
      const y = Math.round(h * i / 4) + 0.5;
      ctx.beginPath();
      ctx.moveTo(0, y);
      ctx.lineTo(w, y);
      ctx.stroke();
    }
    const x = (t) => w - (now - t) / WINDOW_MS * w;
    const y = (v, max) => h - pad - Math.max(0, Math.min(v / max, 1)) *
      (h - 2 * pad);
    const line = (key, max, color) => {
      ctx.strokeStyle = color;
      ctx.lineWidth = 2;
      ctx.beginPath();
      history.forEach((p, i) => {
        /* Steps: a value holds until the next one. The first is drawn
         * from the left edge: it is what the page found. */
        if (i === 0)
          ctx.moveTo(Math.min(0, x(p.t)), y(p[key], max));
        else
          ctx.lineTo(x(p.t), y(history[i - 1][key], max));
        ctx.lineTo(x(p.t), y(p[key], max));
      });
      if (history.length)
        ctx.lineTo(w, y(history[history.length - 1][key], max));
      ctx.stroke();
    };
    const css = getComputedStyle(document.documentElement);
    line('width', wmax, css.getPropertyValue('--width').trim());
    line('force', fmax, css.getPropertyValue('--force').trim());
  }

  function record(s) {
    const now = performance.now();
    history.push({ t: now, width: s.width, force: s.force });
    /* Keep one point older than the window: the line starts at its
     * left edge. */
    while (history.length > 2 && history[1].t < now - WINDOW_MS)
      history.shift();
  }

  function show(s) {
    last = s;
    wsg.state = s;
    showGripper(s);
    showObject(s);
    showReadings(s);
    if (info)
      showFlags(s);
    record(s);
    drawPlot();
    wsg.emit('state', s);
  }

  /* The sidebar's buttons. */
  function act(path) {
    const out = $('result');
    wsg.post(path).then((a) => {
      out.textContent = path.slice(1).toUpperCase() + ': ' +
        (a.body.status || a.body.error);
    });
  }

  /* ---- tabs: the one named in the URL's fragment (#settings) ---- */
  function showTab() {
    const name = (location.hash || '#diagnostics').slice(1);
    const known = document.getElementById('tab-' + name) ? name
      : 'diagnostics';
    document.querySelectorAll('.tab').forEach((t) => {
      t.hidden = t.id !== 'tab-' + known;
    });
    document.querySelectorAll('.tabs button').forEach((b) => {
      b.setAttribute('aria-selected', String(b.dataset.tab === known));
    });
    if (known === 'diagnostics')
      drawPlot();
  }
  document.querySelectorAll('.tabs button').forEach((b) => {
    b.addEventListener('click', () => { location.hash = b.dataset.tab; });
  });
  window.addEventListener('hashchange', showTab);
  showTab();

  /* ---- the communication log ---- */
  const logView = $('log');
  let logLines = [];

  function shown(line) {
    const f = $('log-filter').value;
    return !f || line.includes(f);
  }

  function renderLog() {
    logView.textContent = logLines.filter(shown).join('\n');
    if ($('log-follow').checked)
      logView.scrollTop = logView.scrollHeight;
  }

  function addLog(lines) {
    logLines = logLines.concat(lines);
    if (logLines.length > LOG_LINES)
      logLines = logLines.slice(logLines.length - LOG_LINES);
    const add = lines.filter(shown);
    /* Appending is cheaper than redrawing while the view is not cut. */
    if (add.length && logLines.length < LOG_LINES)
      logView.append((logView.textContent ? '\n' : '') + add.join('\n'));
    else if (add.length)
      renderLog();
    if ($('log-follow').checked)
      logView.scrollTop = logView.scrollHeight;
  }
  $('log-filter').addEventListener('input', renderLog);
  $('log-clear').addEventListener('click', () => {
    logLines = [];
    renderLog();
  });

  /* ---- the scenario: the control channel's commands ---- */
  function control(line) {
    const out = $('scenario-answer');
    return wsg.post('/control', { line }).then((a) => {
      out.textContent = '> ' + line + '\n' + (a.body.answer || a.body.error);
      out.classList.toggle('bad', !a.ok);
      return a;
    });
  }
  const val = (id) => $(id).value.trim();
  const click = (id, fn) => $(id).addEventListener('click', fn);
  click('part-place', () => control('part ' + val('part-width') + ' ' +
    val('part-stiffness')));
  click('part-remove', () => control('part none'));
  click('obstacle-place', () => control('obstacle ' + val('obstacle-width')));
  click('obstacle-remove', () => control('obstacle none'));
  click('fault-on', () => control('fault ' + val('fault-name') + ' on'));
  click('fault-off', () => control('fault ' + val('fault-name') + ' off'));
  click('time-pause', () => control('time pause'));
  click('time-resume', () => control('time resume'));
  click('time-step', () => control('time step ' + val('time-ms')));
  $('scenario').addEventListener('submit', (ev) => {
    ev.preventDefault();
    const line = val('control-line');
    if (line)
      control(line);
  });
  wsg.control = control;

  $('window').textContent = String(WINDOW_MS / 1000);
  $('stop').addEventListener('click', () => act('/stop'));
  $('ack').addEventListener('click', () => act('/ack'));

  fetch('/info.json')
    .then((r) => r.json())
    .then((i) => {
      info = i;
      wsg.info = i;
      $('title').textContent = 'WSG ' + i.stroke + ' mm, SN ' + i.serial;
      $('version').textContent = 'Firmware ' + i.firmware + ', wsgemu ' +
        i.emulator + '.';
      buildFlags();
      if (last)
        show(last);
      wsg.emit('info', i);
    })
    .catch(() => {});

  /* The browser reconnects a stream that broke by itself, but gives up
   * on one the server refused: it takes so many at once (503, with when
   * to try again; docs/web.md). Then the page opens a new one later. */
  const RETRY_MS = 10000;
  function connect() {
    const events = new EventSource('/events');
    events.addEventListener('state', (ev) => show(JSON.parse(ev.data)));
    events.addEventListener('log', (ev) => {
      const lines = ev.data.split('\n');
      addLog(lines);
      wsg.emit('log', lines);
    });
    events.addEventListener('open', () => {
      $('link').textContent = 'live';
      $('link').className = 'link up';
    });
    events.addEventListener('error', () => {
      $('link').className = 'link down';
      if (events.readyState !== EventSource.CLOSED) {
        $('link').textContent = 'disconnected, reconnecting…';
        return;
      }
      $('link').textContent = 'no live view (the server is busy), ' +
        'trying again…';
      setTimeout(connect, RETRY_MS);
    });
  }
  connect();
})();
