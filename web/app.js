/*
 * The web page's life: what the gripper is (/info.json) once, then its
 * state as the server pushes it (/events, a "state" event whenever it
 * changes, none while it does not), drawn as it comes: the fingers and the
 * part, the readings, the flags, the plot. Nothing here polls or runs on a
 * timer, so a page left open on an idle gripper costs nothing. STOP and
 * ACK post to /stop and /ack.
 */
'use strict';

(function () {
  const WINDOW_MS = 10000; /* the plot's span */
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
    showGripper(s);
    showReadings(s);
    if (info)
      showFlags(s);
    record(s);
    drawPlot();
  }

  function act(path) {
    const out = $('result');
    fetch(path, { method: 'POST' })
      .then((r) => r.json())
      .then((j) => { out.textContent = path.slice(1).toUpperCase() + ': ' +
        (j.status || j.error); })
      .catch((e) => { out.textContent = String(e); });
  }

  $('window').textContent = String(WINDOW_MS / 1000);
  $('stop').addEventListener('click', () => act('/stop'));
  $('ack').addEventListener('click', () => act('/ack'));

  fetch('/info.json')
    .then((r) => r.json())
    .then((i) => {
      info = i;
      $('title').textContent = 'WSG ' + i.stroke + ' mm, SN ' + i.serial;
      buildFlags();
      if (last)
        show(last);
    })
    .catch(() => {});

  const events = new EventSource('/events');
  events.addEventListener('state', (ev) => show(JSON.parse(ev.data)));
  events.addEventListener('open', () => {
    $('link').textContent = 'live';
    $('link').className = 'link up';
  });
  events.addEventListener('error', () => {
    /* The browser reconnects by itself. */
    $('link').textContent = 'disconnected, reconnecting…';
    $('link').className = 'link down';
  });
})();
