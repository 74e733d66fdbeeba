/*
 * The Motion tab: the gripper moved from the page, each button a POST
 * /motion (action=move, jog, grasp, release, home, stop) that the daemon
 * runs as the command it stands for (21h, 21h relative, 25h, 26h, 20h,
 * 22h). The answer's status (the manual's name: E_CMD_PENDING for a
 * motion started, or why it was refused) shows under the buttons; the
 * motion itself shows in the sidebar and the Diagnostics tab as the state
 * changes.
 *
 * Element ids: motion-width, motion-speed, motion-move, motion-step,
 * motion-jog-minus, motion-jog-plus, motion-part, motion-grasp-speed,
 * motion-force, motion-grasp, motion-pullback, motion-release-speed,
 * motion-release, motion-home, motion-stop, motion-answer.
 */
'use strict';

(function () {
  const tab = document.getElementById('tab-motion');
  const el = wsg.el;
  const answer = el('p', { id: 'motion-answer', className: 'answer' });

  function num(id, value, unit, props) {
    return el('label', {}, el('input', Object.assign({ type: 'number', id,
      value, step: 'any' }, props || {})), ' ' + unit);
  }

  function button(id, text) {
    return el('button', { type: 'button', id, textContent: text });
  }

  function val(id) {
    return document.getElementById(id).value;
  }

  function run(fields) {
    answer.textContent = '…';
    wsg.post('/motion', fields).then((r) => {
      answer.className = 'answer ' + (r.ok ? 'good' : 'bad');
      answer.textContent = r.body.status
        ? fields.action + ': ' + r.body.status + ' (' + r.body.command + ')'
        : fields.action + ': ' + (r.body.error || 'failed (' + r.status + ')');
    });
  }

  const move = el('fieldset', {}, el('legend', { textContent: 'Move' }),
    'width ', num('motion-width', 50, 'mm', { min: 0 }),
    ' speed ', num('motion-speed', 100, 'mm/s', { min: 0 }),
    ' ', button('motion-move', 'Move'));
  const jog = el('fieldset', {}, el('legend', { textContent: 'Jog' }),
    button('motion-jog-minus', '−'), ' step ',
    num('motion-step', 5, 'mm', { min: 0 }), ' ',
    button('motion-jog-plus', '+'));
  const grasp = el('fieldset', {}, el('legend', { textContent: 'Grasp' }),
    'part width ', num('motion-part', 20, 'mm', { min: 0 }),
    ' speed ', num('motion-grasp-speed', 50, 'mm/s', { min: 0 }),
    ' force ', num('motion-force', 40, 'N', { min: 0 }),
    ' ', button('motion-grasp', 'Grasp'));
  const release = el('fieldset', {}, el('legend', { textContent: 'Release' }),
    'pull-back ', num('motion-pullback', 10, 'mm', { min: 0 }),
    ' speed ', num('motion-release-speed', 50, 'mm/s', { min: 0 }),
    ' ', button('motion-release', 'Release'));
  const other = el('div', { className: 'actions' },
    button('motion-home', 'Home'), button('motion-stop', 'Stop'));

  /* Where the fingers are while they move, without leaving the tab. */
  const live = el('p', { id: 'motion-live', className: 'live' });
  wsg.on('state', (s) => {
    live.textContent = 'Width ' + s.width.toFixed(1) + ' mm, speed ' +
      s.speed.toFixed(1) + ' mm/s, force ' + s.force.toFixed(1) + ' N';
  });

  answer.setAttribute('aria-live', 'polite');
  tab.append(el('h2', { textContent: 'Motion' }), live, move, jog, grasp,
    release, other, answer);

  function on(id, fn) {
    document.getElementById(id).addEventListener('click', fn);
  }

  on('motion-move', () => run({ action: 'move', width: val('motion-width'),
    speed: val('motion-speed') }));
  on('motion-jog-minus', () => run({ action: 'jog',
    step: String(-Number(val('motion-step'))), speed: val('motion-speed') }));
  on('motion-jog-plus', () => run({ action: 'jog', step: val('motion-step'),
    speed: val('motion-speed') }));
  on('motion-grasp', () => run({ action: 'grasp', width: val('motion-part'),
    speed: val('motion-grasp-speed'), force: val('motion-force') }));
  on('motion-release', () => run({ action: 'release',
    pullback: val('motion-pullback'),
    speed: val('motion-release-speed') }));
  on('motion-home', () => run({ action: 'home' }));
  on('motion-stop', () => run({ action: 'stop' }));
})();
