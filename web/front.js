// The Pareto front of a result directory (/api/result "front"): a 2D scatter of two chosen
// objectives drawn as SVG in the #front panel; clicking a point shows that design (onSelect
// redraws the mechanism) and its objectives and design in the panel. State for tests on
// `state` (window.hapsynView): frontCount, frontAxes, front3d, selectedPoint, selectedDesign,
// frontPointPosition(i) -> the point's centre in client pixels (and its depth in 3D),
// selectFrontPoint(i), showFront3d(on). A front of three or more objectives opens in a 3D scatter
// (front3d.js, given as `scatter3d`) with a third objective; a check box turns it to 2D.
import { axes, element, extent } from 'hapsyn/plots.js';

const WIDTH = 360, HEIGHT = 260, MARGIN = { left: 56, right: 12, top: 10, bottom: 40 };

function format(v) {
  return v === null || v === undefined ? '–' : Number(v).toPrecision(4);
}

function label(objective) {
  return `${objective.name} (${objective.sense === 'maximize' ? 'max' : 'min'})` + (objective.unit ? ` [${objective.unit}]` : '');
}

function axisSelect(id, objectives, chosen) {
  const select = document.getElementById(id);
  select.textContent = '';
  objectives.forEach((o, i) => {
    const option = document.createElement('option');
    option.value = String(i);
    option.textContent = label(o);
    select.appendChild(option);
  });
  select.value = String(chosen);
  return select;
}

function describe(front, point) {
  const objectives = front.objectives.map(o => `${o.name} = ${format(point.objectives[o.name])}${o.unit ? ' ' + o.unit : ''}`);
  const design = Object.entries(point.design).map(([k, v]) => `${k} = ${Array.isArray(v) ? '[' + v.map(format).join(', ') + ']' : format(v)}`);
  const drawn = point.drawn_sample === null ? 'reaches none of the samples tried: not drawn' : `drawn at sample ${point.drawn_sample}`;
  return `objectives: ${objectives.join(', ')}; design: ${design.join(', ')}; ${drawn}`;
}

// The z list and the 3D check box, added to the panel for a front of three or more objectives.
function controls3d(objectives) {
  const ySelect = document.getElementById('front-y');
  const label = document.createElement('label');
  label.htmlFor = 'front-z';
  label.textContent = ' z ';
  const zSelect = document.createElement('select');
  zSelect.id = 'front-z';
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.id = 'front-3d';
  box.checked = true;
  const boxLabel = document.createElement('label');
  boxLabel.htmlFor = 'front-3d';
  boxLabel.textContent = '3D';
  ySelect.after(label, zSelect, ' ', box, boxLabel);
  return [axisSelect('front-z', objectives, 2), box];
}

/// Shows `result.front` in #front (hidden when there is none). onSelect(point) draws the design;
/// scatter3d: front3d.js's, for fronts of three or more objectives.
export function setupFront(result, state, onSelect, scatter3d) {
  const front = result.front;
  const panel = document.getElementById('front');
  state.frontCount = front ? front.points.length : 0;
  state.selectedPoint = null;
  state.selectedDesign = null;
  if (!front || !front.points.length || front.objectives.length < 2) return;
  panel.hidden = false;
  document.getElementById('front-title').textContent =
    `Pareto front: ${front.points.length} point${front.points.length === 1 ? '' : 's'}`;
  const svg = document.getElementById('front-plot');
  svg.setAttribute('viewBox', `0 0 ${WIDTH} ${HEIGHT}`);
  svg.setAttribute('width', WIDTH);
  svg.setAttribute('height', HEIGHT);
  const xSelect = axisSelect('front-x', front.objectives, 0);
  const ySelect = axisSelect('front-y', front.objectives, 1);
  let circles = [];
  let view = null, zSelect = null, box = null;
  state.front3d = false;
  if (front.objectives.length >= 3 && scatter3d) {
    [zSelect, box] = controls3d(front.objectives);
    const holder = document.createElement('div');
    svg.after(holder);
    view = scatter3d(holder, WIDTH, HEIGHT, index => select(index));
  }

  const select = index => {
    circles.forEach((c, i) => c.setAttribute('class', i === index ? 'point selected' : 'point'));
    const point = front.points[index];
    state.selectedPoint = index;
    state.selectedDesign = point.design;
    if (view) view.select(index);
    document.getElementById('front-info').textContent = `point ${index + 1}: ${describe(front, point)}`;
    onSelect(point);
  };

  const draw = () => {
    state.front3d = Boolean(view && box.checked);
    svg.style.display = state.front3d ? 'none' : '';
    if (view) view.canvas.style.display = state.front3d ? '' : 'none';
    if (state.front3d) {
      const axes = [xSelect, ySelect, zSelect].map(s => front.objectives[Number(s.value)]);
      state.frontAxes = axes.map(o => o.name);
      view.draw(...axes.map(o => front.points.map(p => p.objectives[o.name])));
      if (state.selectedPoint !== null) view.select(state.selectedPoint);
      return;
    }
    const [ox, oy] = [front.objectives[Number(xSelect.value)], front.objectives[Number(ySelect.value)]];
    state.frontAxes = [ox.name, oy.name];
    svg.textContent = '';
    const xs = front.points.map(p => p.objectives[ox.name]), ys = front.points.map(p => p.objectives[oy.name]);
    const [px, py] = axes(svg, { width: WIDTH, height: HEIGHT, margin: MARGIN }, extent(xs), extent(ys), label(ox), label(oy));
    circles = front.points.map((p, i) => {
      const x = xs[i], y = ys[i];
      const finite = x !== null && y !== null && Number.isFinite(x) && Number.isFinite(y);
      const c = element('circle', { cx: finite ? px(x) : -10, cy: finite ? py(y) : -10, r: 5, class: 'point' }, svg);
      element('title', {}, c).textContent = `point ${i + 1}: ${ox.name} = ${format(x)}, ${oy.name} = ${format(y)}`;
      c.addEventListener('click', () => select(i));
      return c;
    });
    if (state.selectedPoint !== null) circles[state.selectedPoint].setAttribute('class', 'point selected');
  };
  xSelect.addEventListener('change', draw);
  if (view) {
    zSelect.addEventListener('change', draw);
    box.addEventListener('change', draw);
  }
  ySelect.addEventListener('change', draw);
  draw();
  state.frontPointPosition = index => {
    if (state.front3d) return view.position(index);
    const box = circles[index].getBoundingClientRect();
    return [box.left + box.width / 2, box.top + box.height / 2];
  };
  state.selectFrontPoint = index => select(index);
  state.showFront3d = on => {
    if (!view) return false;
    box.checked = on;
    draw();
    return true;
  };
}
