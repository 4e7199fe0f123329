// A solver's convergence history and runs (/api/result "statistics"): a line plot of one history
// column per generation (ga: one line per run; nsga2: its one history) and the runs' and
// clusters' tables, in the #runs panel. State for tests on `state` (window.hapsynView):
// convergenceColumn, convergenceSeries (lines drawn), convergencePoints (points per line),
// runRows, clusterRows.
const SVG = 'http://www.w3.org/2000/svg';
const WIDTH = 360, HEIGHT = 200, MARGIN = { left: 56, right: 12, top: 10, bottom: 34 };
// Colour-blind-safe line colours (Okabe-Ito).
const COLOURS = ['#0072b2', '#d55e00', '#009e73', '#cc79a7', '#e69f00', '#56b4e9', '#000000', '#f0e442'];

// An SVG element with its attributes, appended to parent when given (front.js uses it too).
export function element(name, attributes, parent) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attributes)) e.setAttribute(k, String(v));
  if (parent) parent.appendChild(e);
  return e;
}

function format(v) {
  return v === null || v === undefined ? '–' : typeof v === 'number' ? Number(v).toPrecision(4) : String(v);
}

// An axis label: three significant digits, exponent notation for small or large magnitudes.
export function tick(v) {
  const m = Math.abs(v);
  return m !== 0 && (m < 1e-2 || m >= 1e5) ? v.toExponential(1) : String(Number(v.toPrecision(3)));
}

// [lo, hi] of the finite values, widened by 5 % (a single value gets +-1 % or +-1).
export function extent(values) {
  const finite = values.filter(v => v !== null && Number.isFinite(v));
  if (!finite.length) return [0, 1];
  let lo = Math.min(...finite), hi = Math.max(...finite);
  if (hi === lo) return lo === 0 ? [-1, 1] : [lo - Math.abs(lo) * 0.01, hi + Math.abs(hi) * 0.01];
  return [lo - (hi - lo) * 0.05, hi + (hi - lo) * 0.05];
}

/// The frame of an x-y plot into `svg`: its box ({width, height, margin: {left, right, top,
/// bottom}}), five ticks on each axis over [x0, x1] and [y0, y1], and the axis labels. Returns
/// [px, py], the maps from values to SVG coordinates (front.js draws its scatter with it too).
export function axes(svg, box, [x0, x1], [y0, y1], xLabel, yLabel) {
  const { width, height, margin } = box;
  const px = v => margin.left + (v - x0) / (x1 - x0) * (width - margin.left - margin.right);
  const py = v => height - margin.bottom - (v - y0) / (y1 - y0) * (height - margin.top - margin.bottom);
  element('rect', { x: margin.left, y: margin.top, width: width - margin.left - margin.right,
                    height: height - margin.top - margin.bottom, class: 'frame' }, svg);
  for (let k = 0; k <= 4; ++k) {
    const vx = x0 + (x1 - x0) * k / 4, vy = y0 + (y1 - y0) * k / 4;
    element('text', { x: px(vx), y: height - margin.bottom + 13, 'text-anchor': 'middle', class: 'tick' }, svg).textContent = tick(vx);
    element('text', { x: margin.left - 4, y: py(vy) + 4, 'text-anchor': 'end', class: 'tick' }, svg).textContent = tick(vy);
  }
  element('text', { x: (margin.left + width - margin.right) / 2, y: height - 5, 'text-anchor': 'middle', class: 'axis' }, svg)
    .textContent = xLabel;
  const mid = (margin.top + height - margin.bottom) / 2;
  element('text', { x: 12, y: mid, 'text-anchor': 'middle', class: 'axis', transform: `rotate(-90 12 ${mid})` }, svg)
    .textContent = yLabel;
  return [px, py];
}

/// Draws `series` ([{label, x: [], y: []}], null y values skipped) into `svg`; returns the
/// number of points drawn per series.
export function linePlot(svg, series, xLabel, yLabel) {
  svg.textContent = '';
  svg.setAttribute('viewBox', `0 0 ${WIDTH} ${HEIGHT}`);
  svg.setAttribute('width', WIDTH);
  svg.setAttribute('height', HEIGHT);
  const [px, py] = axes(svg, { width: WIDTH, height: HEIGHT, margin: MARGIN },
                        extent(series.flatMap(s => s.x)), extent(series.flatMap(s => s.y)), xLabel, yLabel);
  return series.map((s, i) => {
    const points = [];
    s.x.forEach((x, k) => {
      const y = s.y[k];
      if (x !== null && y !== null && Number.isFinite(x) && Number.isFinite(y)) points.push(`${px(x).toFixed(1)},${py(y).toFixed(1)}`);
    });
    const line = element('polyline', { points: points.join(' '), class: 'line', stroke: COLOURS[i % COLOURS.length] }, svg);
    element('title', {}, line).textContent = s.label;
    return points.length;
  });
}

/// A table of `rows` (arrays of cells) under `header` into `container`.
export function table(container, header, rows) {
  container.textContent = '';
  const t = document.createElement('table');
  const head = t.createTHead().insertRow();
  for (const h of header) head.appendChild(document.createElement('th')).textContent = h;
  const body = t.createTBody();
  for (const row of rows) {
    const tr = body.insertRow();
    for (const cell of row) tr.insertCell().textContent = format(cell);
  }
  container.appendChild(t);
}

// A history's columns by name: its arrays, and the arrays of a nested object as "key.name"
// (nsga2's "ideal": {objective: [...]}); scalars (the stride) are no column.
function flatten(history) {
  const columns = {};
  for (const [key, value] of Object.entries(history)) {
    if (Array.isArray(value)) columns[key] = value;
    else if (value && typeof value === 'object') {
      for (const [name, inner] of Object.entries(value)) if (Array.isArray(inner)) columns[`${key}.${name}`] = inner;
    }
  }
  return columns;
}

// The histories to plot: [{label, history}] (ga: each run's; nsga2: statistics.history).
function histories(statistics) {
  if (Array.isArray(statistics.runs)) {
    return statistics.runs.filter(r => r.history).map(r => ({ label: `run ${r.run + 1}`, history: flatten(r.history) }));
  }
  return statistics.history ? [{ label: 'history', history: flatten(statistics.history) }] : [];
}

/// Shows `result.statistics` in #runs (hidden when it has no history).
export function setupRuns(result, objectives, state) {
  const statistics = result.statistics || {};
  const lines = histories(statistics);
  state.convergenceSeries = 0;
  state.runRows = 0;
  state.clusterRows = 0;
  if (!lines.length) return;
  document.getElementById('runs').hidden = false;
  // Every column but generation, of any history.
  const columns = [...new Set(lines.flatMap(l => Object.keys(l.history)))]
    .filter(c => c !== 'generation' && c !== 'fidelity');
  const select = document.getElementById('runs-column');
  for (const c of columns) select.appendChild(document.createElement('option')).textContent = c;
  // ga: the best score; nsga2: the first objective's ideal.
  const first = 'ideal.' + objectives[0];
  select.value = columns.includes('best') ? 'best' : columns.includes(first) ? first : columns[0];
  const draw = () => {
    const column = select.value;
    const series = lines.filter(l => l.history[column])
      .map(l => ({ label: l.label, x: l.history.generation, y: l.history[column] }));
    const counts = linePlot(document.getElementById('runs-plot'), series, 'generation', column);
    state.convergenceColumn = column;
    state.convergenceSeries = series.length;
    state.convergencePoints = counts;
  };
  select.addEventListener('change', draw);
  draw();
  if (Array.isArray(statistics.runs)) {
    const rows = statistics.runs.map(r => [r.run + 1, r.status, r.generations, r.score ?? null,
                                           ...objectives.map(o => (r.objectives || {})[o] ?? null)]);
    table(document.getElementById('runs-table'), ['run', 'status', 'generations', 'score', ...objectives], rows);
    state.runRows = rows.length;
  }
  const clusters = statistics.clusters && statistics.clusters.clusters;
  if (Array.isArray(clusters)) {
    const variables = statistics.clusters.variables || [];
    const rows = clusters.map((c, i) => [i + 1, c.size, c.runs.map(r => r + 1).join(' '), c.mean_score, c.best_score,
                                         ...variables.map(v => c.centroid[v])]);
    table(document.getElementById('clusters-table'), ['cluster', 'size', 'runs', 'mean score', 'best score', ...variables], rows);
    state.clusterRows = rows.length;
  }
}

/// Draws one bar per row (`labels`, `values`, null skipped) into `svg`; returns the bars drawn.
export function barPlot(svg, labels, values, yLabel) {
  svg.textContent = '';
  const height = HEIGHT + 40;  // room for the rotated labels
  svg.setAttribute('viewBox', `0 0 ${WIDTH} ${height}`);
  svg.setAttribute('width', WIDTH);
  svg.setAttribute('height', height);
  const finite = values.filter(v => v !== null && Number.isFinite(v));
  let [y0, y1] = extent([0, ...finite]);
  if (finite.every(v => v >= 0)) y0 = 0;  // bars of non-negative values stand on the axis
  const bottom = HEIGHT - MARGIN.bottom;
  const py = v => bottom - (v - y0) / (y1 - y0) * (bottom - MARGIN.top);
  const slot = (WIDTH - MARGIN.left - MARGIN.right) / Math.max(values.length, 1);
  element('rect', { x: MARGIN.left, y: MARGIN.top, width: WIDTH - MARGIN.left - MARGIN.right, height: bottom - MARGIN.top, class: 'frame' }, svg);
  for (let k = 0; k <= 4; ++k) {
    const vy = y0 + (y1 - y0) * k / 4;
    element('text', { x: MARGIN.left - 4, y: py(vy) + 4, 'text-anchor': 'end', class: 'tick' }, svg).textContent = tick(vy);
  }
  const mid = (MARGIN.top + bottom) / 2;
  element('text', { x: 12, y: mid, 'text-anchor': 'middle', class: 'axis', transform: `rotate(-90 12 ${mid})` }, svg).textContent = yLabel;
  let bars = 0;
  values.forEach((v, i) => {
    const x = MARGIN.left + slot * (i + 0.15);
    const lx = MARGIN.left + slot * (i + 0.5);
    element('text', { x: lx, y: bottom + 10, 'text-anchor': 'end', class: 'tick', transform: `rotate(-30 ${lx} ${bottom + 10})` }, svg)
      .textContent = labels[i];
    if (v === null || !Number.isFinite(v)) return;
    const top = Math.min(py(v), py(0)), h = Math.abs(py(v) - py(0));
    const bar = element('rect', { x, y: top, width: slot * 0.7, height: Math.max(h, 0.5), class: 'bar', fill: COLOURS[0] }, svg);
    element('title', {}, bar).textContent = `${labels[i]}: ${format(v)}`;
    ++bars;
  });
  return bars;
}

/// Shows `result.batch` (a sweep's or comparison's table) in #batch: a bar plot of a chosen
/// column over the runs and the table (hidden when there is none).
export function setupBatch(result, state) {
  const batch = result.batch;
  state.batchKind = batch ? batch.kind : null;
  state.batchRows = batch ? batch.rows.length : 0;
  if (!batch) return;
  document.getElementById('batch').hidden = false;
  document.getElementById('batch-title').textContent =
    `${batch.kind === 'sweep' ? 'Sweep' : 'Comparison'}: ${batch.rows.length} runs (3D view: ${batch.shown})`;
  const columns = [...new Set(batch.rows.flatMap(r => Object.keys(r.values)))];
  const select = document.getElementById('batch-column');
  for (const c of columns) select.appendChild(document.createElement('option')).textContent = c;
  const preferred = ['errors.objective_error', 'wall_time_s', 'run_time_s'].find(c => columns.includes(c));
  select.value = preferred || columns[0];
  const labels = batch.rows.map(r => r.label);
  const draw = () => {
    const column = select.value;
    state.batchColumn = column;
    state.batchBars = barPlot(document.getElementById('batch-plot'), labels, batch.rows.map(r => r.values[column] ?? null), column);
  };
  select.addEventListener('change', draw);
  draw();
  table(document.getElementById('batch-table'), ['run', ...columns], batch.rows.map(r => [r.label, ...columns.map(c => r.values[c] ?? null)]));
  state.selectBatchColumn = column => {
    if (!columns.includes(column)) return false;
    select.value = column;
    draw();
    return true;
  };
}
