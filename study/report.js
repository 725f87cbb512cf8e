function niceTicks(lo, hi, n) {
  const span = hi - lo || 1, raw = span / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map(m => m * mag).find(s => span / s <= n) || 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) out.push(+v.toPrecision(12));
  return out;
}
function chart(id, spec) {
  const W = 1000, H = spec.height || 300, m = {l: 60, r: 15, t: 24, b: 40};
  const ns = 'http://www.w3.org/2000/svg';
  const fx = spec.logx ? Math.log10 : (v => v), fy = spec.logy ? Math.log10 : (v => v);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const s of spec.series) for (let i = 0; i < s.x.length; i++) {
    const X = fx(s.x[i]), Y = fy(s.y[i]);
    if (!isFinite(X) || !isFinite(Y)) continue;
    x0 = Math.min(x0, X); x1 = Math.max(x1, X); y0 = Math.min(y0, Y); y1 = Math.max(y1, Y);
  }
  if (spec.ymin !== undefined) y0 = Math.max(y0, spec.ymin);
  const pad = (y1 - y0) * 0.05 || 1; y0 -= pad; y1 += pad;
  const sx = v => m.l + (fx(v) - x0) / (x1 - x0 || 1) * (W - m.l - m.r);
  const sy = v => H - m.b - (Math.max(fy(v), y0) - y0) / (y1 - y0) * (H - m.t - m.b);
  const svg = document.createElementNS(ns, 'svg');
  svg.setAttribute('viewBox', `0 0 ${W} ${H}`); svg.setAttribute('width', '100%');
  const el = (tag, attrs, text) => { const e = document.createElementNS(ns, tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]); if (text !== undefined) e.textContent = text;
    svg.appendChild(e); return e; };
  const xt = spec.logx ? [] : niceTicks(x0, x1, 10), yt = spec.logy ? [] : niceTicks(y0, y1, 6);
  if (spec.logx) for (let e = Math.floor(x0); e <= Math.ceil(x1); e++) xt.push(Math.pow(10, e));
  if (spec.logy) for (let e = Math.floor(y0); e <= Math.ceil(y1); e++) yt.push(Math.pow(10, e));
  for (const v of xt) { const X = sx(v); if (X < m.l - 1 || X > W - m.r + 1) continue;
    el('line', {x1: X, x2: X, y1: m.t, y2: H - m.b, stroke: '#eee'});
    el('text', {x: X, y: H - m.b + 14, 'font-size': 11, 'text-anchor': 'middle'}, +v.toPrecision(4)); }
  for (const v of yt) { const Y = sy(v); if (Y < m.t - 1 || Y > H - m.b + 1) continue;
    el('line', {x1: m.l, x2: W - m.r, y1: Y, y2: Y, stroke: '#eee'});
    el('text', {x: m.l - 4, y: Y + 4, 'font-size': 11, 'text-anchor': 'end'}, +v.toPrecision(4)); }
  el('rect', {x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b, fill: 'none', stroke: '#999'});
  el('text', {x: W / 2, y: H - 6, 'font-size': 12, 'text-anchor': 'middle'}, spec.xlabel || '');
  el('text', {x: 12, y: H / 2, 'font-size': 12, 'text-anchor': 'middle',
              transform: `rotate(-90 12 ${H / 2})`}, spec.ylabel || '');
  el('text', {x: m.l, y: 15, 'font-size': 13, 'font-weight': 'bold'}, spec.title || '');
  const colors = ['#222', '#d62728', '#1f77b4', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b'];
  spec.series.forEach((s, k) => {
    const c = s.color || colors[k % colors.length];
    if (s.stem) { for (let i = 0; i < s.x.length; i++) el('line', {x1: sx(s.x[i]), x2: sx(s.x[i]),
        y1: sy(s.y[i]), y2: H - m.b, stroke: c, 'stroke-width': 0.6}); return; }
    let d = '';
    for (let i = 0; i < s.x.length; i++) { if (!isFinite(fy(s.y[i]))) continue;
      d += (d ? 'L' : 'M') + sx(s.x[i]).toFixed(1) + ' ' + sy(s.y[i]).toFixed(1); }
    el('path', {d, fill: 'none', stroke: c, 'stroke-width': s.width || 1.2,
                'stroke-dasharray': s.dash || ''});
    if (s.mark !== undefined) el('circle', {cx: sx(s.x[s.mark]), cy: sy(s.y[s.mark]), r: 4, fill: c});
  });
  const box = document.getElementById(id);
  box.appendChild(svg);
  const legend = document.createElement('div'); legend.className = 'legend';
  spec.series.forEach((s, k) => { const sp = document.createElement('span');
    sp.innerHTML = `<b style="color:${s.color || colors[k % colors.length]}">&#9644;</b> ${s.name}`;
    legend.appendChild(sp); });
  box.appendChild(legend);
}
function draw() {
  const D = DATA;
  let n = 0;
  const add = (section, spec) => { const div = document.createElement('div'); div.className = 'plot';
    div.id = 'plot' + (n++); document.getElementById(section).appendChild(div); chart(div.id, spec); };
  for (const r of D.responses) add('responses', {title: r.title, xlabel: 't (s)', ylabel: 'y_dwe (mm)',
      series: r.series});
  for (const g of D.gamma) add('gamma', {title: g.title, xlabel: 'γ', ylabel: 'Nrmse (%)', series: g.series,
      ymin: g.ymin, height: 260});
  for (const f of D.regimes) add('regimes', {title: f.title, xlabel: 't (s)', ylabel: 'level (mm)',
      series: f.series, height: 260});
  const s = D.spectrum;
  add('spectrum', {title: 'Magnitude of the Fourier transform of a unit-amplitude PRBS and of a unit step',
      xlabel: 'ω (rad/s)', ylabel: '|F(ω)|', logy: true, height: 320, series: [
      {name: 'PRBS lines (recorded command)', x: s.omega, y: s.magnitude, stem: true, color: '#1f77b4'},
      {name: 'envelope Tc √(N+1) |sinc|', x: s.omega, y: s.envelope, color: '#222'},
      {name: 'unit step 1/ω', x: s.omega, y: s.step, color: '#d62728'},
      {name: 'envelope max/√2 (−3 dB)', x: [s.omega[0], s.omega[s.omega.length - 1]],
       y: [s.peak / Math.SQRT2, s.peak / Math.SQRT2], dash: '4 3', color: '#2ca02c'}]});
}
draw();
