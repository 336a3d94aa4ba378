// The error estimate against time, log scale, for the current run and the
// last few before it (to compare settings).

import { el } from "./dom.js";
import { fmtTime } from "./format.js";
import { on, state } from "./state.js";

function addChartPoint(s) {
  if (s.error_estimate == null || !(s.error_estimate > 0) || !(s.elapsed_ms >= 0)) return;
  let series = state.chart[state.chart.length - 1];
  if (!series || series.generation !== s.generation || series.session !== s.id) {
    series = { generation: s.generation, session: s.id, points: [] };
    state.chart.push(series);
    // Keep the last few runs with more than a point or two, to compare settings.
    state.chart = state.chart.filter((c, i, all) => i === all.length - 1 || c.points.length > 2).slice(-4);
  }
  const last = series.points[series.points.length - 1];
  if (!last || s.elapsed_ms > last[0]) series.points.push([s.elapsed_ms, s.error_estimate]);
  if (series.points.length > 2000) series.points.splice(0, series.points.length - 2000);
  scheduleChart();
}

let chartQueued = false;
export function scheduleChart() {
  if (chartQueued) return;
  chartQueued = true;
  requestAnimationFrame(() => { chartQueued = false; drawChart(); });
}

export function drawChart() {
  const c = el.chart;
  const dpr = window.devicePixelRatio || 1;
  const cw = c.clientWidth;
  const ch = c.clientHeight;
  if (!cw || !ch) return;
  if (c.width !== Math.round(cw * dpr) || c.height !== Math.round(ch * dpr)) {
    c.width = Math.round(cw * dpr);
    c.height = Math.round(ch * dpr);
  }
  const g = c.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, cw, ch);
  const styles = getComputedStyle(c);
  const fg = styles.color;
  g.font = "10px ui-monospace, monospace";
  g.fillStyle = fg;
  const series = state.chart.filter((s) => s.points.length > 0);
  const pad = { l: 42, r: 8, t: 6, b: 16 };
  const pw = cw - pad.l - pad.r;
  const ph = ch - pad.t - pad.b;
  if (!series.length) {
    g.globalAlpha = 0.6;
    g.fillText("waiting for an error estimate", pad.l, pad.t + ph / 2);
    g.globalAlpha = 1;
    return;
  }
  let tMax = 0;
  let eMin = Infinity;
  let eMax = 0;
  for (const s of series) {
    for (const [t, e] of s.points) {
      tMax = Math.max(tMax, t);
      eMin = Math.min(eMin, e);
      eMax = Math.max(eMax, e);
    }
  }
  tMax = Math.max(tMax, 1000);
  let lo = Math.floor(Math.log10(eMin) * 2) / 2;
  let hi = Math.ceil(Math.log10(eMax) * 2) / 2;
  if (hi - lo < 1) { hi = lo + 1; }
  const x = (t) => pad.l + (t / tMax) * pw;
  const y = (e) => pad.t + ((hi - Math.log10(e)) / (hi - lo)) * ph;
  // Grid: decades (labelled in percent) and the time axis.
  g.strokeStyle = fg;
  g.lineWidth = 1;
  g.globalAlpha = 0.25;
  g.strokeRect(pad.l, pad.t, pw, ph);
  g.globalAlpha = 1;
  g.textAlign = "right";
  g.textBaseline = "middle";
  for (let d = Math.ceil(lo); d <= Math.floor(hi); d++) {
    const yy = y(10 ** d);
    g.globalAlpha = 0.25;
    g.beginPath(); g.moveTo(pad.l, yy); g.lineTo(pad.l + pw, yy); g.stroke();
    g.globalAlpha = 0.8;
    const pct = 100 * 10 ** d;
    g.fillText(`${pct >= 1 ? pct.toFixed(0) : pct.toPrecision(1)}%`, pad.l - 4, yy);
  }
  g.textAlign = "left";
  g.textBaseline = "alphabetic";
  g.globalAlpha = 0.8;
  g.fillText("0", pad.l, ch - 3);
  g.textAlign = "right";
  g.fillText(fmtTime(tMax), pad.l + pw, ch - 3);
  g.textAlign = "left";
  // 1/sqrt(t) from the current run's first point: where the curve flattens
  // out above this line, more time buys less than Monte Carlo promises.
  const cur = series[series.length - 1];
  const [t0, e0] = cur.points[0];
  if (t0 > 0) {
    g.setLineDash([3, 3]);
    g.globalAlpha = 0.4;
    g.beginPath();
    for (let i = 0; i <= 40; i++) {
      const t = t0 + ((tMax - t0) * i) / 40;
      const e = e0 * Math.sqrt(t0 / t);
      if (i === 0) g.moveTo(x(t), y(e)); else g.lineTo(x(t), y(e));
    }
    g.stroke();
    g.setLineDash([]);
  }
  const accent = styles.getPropertyValue("--accent").trim() || "#4cc3ff";
  series.forEach((s, i) => {
    const current = i === series.length - 1;
    g.globalAlpha = current ? 1 : 0.35;
    g.strokeStyle = current ? accent : fg;
    g.lineWidth = current ? 1.5 : 1;
    g.beginPath();
    s.points.forEach(([t, e], j) => {
      if (j === 0) g.moveTo(x(t), y(e)); else g.lineTo(x(t), y(e));
    });
    g.stroke();
  });
  g.globalAlpha = 1;
}

on("status", (s, fromStream) => { if (fromStream) addChartPoint(s); });
