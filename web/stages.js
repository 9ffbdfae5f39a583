// The capture's stage table and the time format, shared by the live-training page (train.js: the stages as they
// run) and the capture report (report.js: the stages of a finished capture, as report.md lists them).
export function fmtTime(s) {
  if (s == null || !isFinite(s)) return '–';
  s = Math.round(s);
  const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = s % 60;
  return (h ? `${h}:${String(m).padStart(2, '0')}` : `${m}`) + `:${String(sec).padStart(2, '0')}`;
}

// Fills `table` with one row per stage {name, state: done|running|pending|skipped, seconds, note, time?}; `time`
// (report.md's text, e.g. the poses stage's parts) replaces the formatted seconds when present.
export function fillStages(table, stages) {
  table.innerHTML = '';
  for (const s of stages) {
    const tr = table.insertRow();
    tr.insertCell().textContent = s.name;
    const st = tr.insertCell(); st.textContent = s.state; st.className = s.state;
    tr.insertCell().textContent = s.time != null ? s.time : s.seconds != null ? fmtTime(s.seconds) : '';
    tr.insertCell().textContent = s.note || '';
  }
}
