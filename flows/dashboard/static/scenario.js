// The scenario card: the before/after frame slider and the bird's-eye-view animation of the log's and the edit's
// paths, both from the page's JSON twin (/api/scenarios/...). No framework, no outside fetch.
"use strict";

const SVG_NS = "http://www.w3.org/2000/svg";

function svgEl(name, attrs, parent) {
  const el = document.createElementNS(SVG_NS, name);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, v);
  if (parent) parent.appendChild(el);
  return el;
}

// ---------------------------------------------------------------------------------------------- frames
function setupFrames(pictures) {
  const slider = document.getElementById("frame");
  if (!slider || !pictures) return;
  const label = document.getElementById("frame-label");
  const byCamera = new Map(pictures.cameras.map((c) => [c.camera, new Map(c.frames.map((p) => [p.frame, p]))]));
  function show(index) {
    const frame = pictures.frames[index];
    label.textContent = String(frame);
    document.querySelectorAll("figure.pair").forEach((fig) => {
      const pair = byCamera.get(fig.dataset.camera)?.get(frame);
      fig.dataset.frame = String(frame);
      fig.classList.toggle("missing", !pair);
      if (!pair) return;
      const before = fig.querySelector("img.before");
      const after = fig.querySelector("img.after");
      if (before && pair.before) { before.src = `/files/${pair.before}`; before.alt = `${fig.dataset.camera} before, frame ${frame}`; }
      if (after) { after.src = `/files/${pair.after}`; after.alt = `${fig.dataset.camera} after, frame ${frame}`; }
    });
  }
  slider.addEventListener("input", () => show(Number(slider.value)));
  slider.dataset.ready = "true";  // the card's data has arrived: the slider now changes the frames
}

// ---------------------------------------------------------------------------------------------- BEV
function boxTransform(pose) {
  return `translate(${pose[0]} ${pose[1]}) rotate(${(pose[2] * 180) / Math.PI})`;
}

function polyPoints(poses) {
  return poses.filter((p) => p).map((p) => `${p[0]},${p[1]}`).join(" ");
}

function setupBev(bev) {
  const svg = document.getElementById("bev");
  if (!svg || !bev) return;
  const [x0, y0, x1, y1] = bev.bounds;
  const half = Math.max(x1 - x0, y1 - y0) / 2;
  const cx = (x0 + x1) / 2;
  const cy = (y0 + y1) / 2;
  svg.setAttribute("viewBox", `${cx - half} ${-(cy + half)} ${2 * half} ${2 * half}`);
  const world = svgEl("g", { transform: "scale(1 -1)" }, svg);  // y up
  for (const shape of bev.map) {
    svgEl(shape.closed ? "polygon" : "polyline", { class: `map-${shape.kind}`, points: polyPoints(shape.points) },
      world);
  }
  const changed = bev.agents.filter((a) => a.source !== "log");
  for (const a of changed) {
    if (a.log.length) svgEl("polyline", { class: `path ${a.source === "removed" ? "removed" : "log"}`, points: polyPoints(a.log) }, world);
    if (a.edited.length) svgEl("polyline", { class: `path ${a.source}`, points: polyPoints(a.edited) }, world);
  }
  const boxes = [];
  for (const a of bev.agents) {
    const kind = a.object_id === "ego" ? "ego" : a.source;
    const rect = { x: -a.length / 2, y: -a.width / 2, width: a.length, height: a.width };
    if (a.source !== "log" && a.log.length && a.edited.length) {  // where the log had it
      boxes.push({ el: svgEl("rect", { ...rect, class: "box ghost" }, world), poses: a.log });
    }
    const poses = a.edited.length ? a.edited : a.log;
    const el = svgEl("rect", { ...rect, class: `box ${kind}`, "data-agent": a.object_id }, world);
    svgEl("title", {}, el).textContent = `${a.object_id} (${a.category}, ${a.source})`;
    boxes.push({ el, poses });
  }
  const slider = document.getElementById("bev-step");
  const label = document.getElementById("bev-label");
  const button = document.getElementById("bev-play");
  function draw(step) {
    svg.dataset.step = String(step);
    for (const b of boxes) {
      const pose = b.poses[step];
      b.el.style.display = pose ? "" : "none";
      if (pose) b.el.setAttribute("transform", boxTransform(pose));
    }
    slider.value = String(step);
    label.textContent = `frame ${bev.frames[step]} · ${bev.times[step].toFixed(1)} s`;
  }
  const dt = bev.times.length > 1 ? (bev.times[bev.times.length - 1] - bev.times[0]) / (bev.times.length - 1) : 0.1;
  let timer = null;
  function stop() { clearInterval(timer); timer = null; button.textContent = "Play"; svg.dataset.playing = "false"; }
  function play() {
    timer = setInterval(() => draw((Number(slider.value) + 1) % bev.frames.length), Math.max(40, dt * 1000));
    button.textContent = "Pause";
    svg.dataset.playing = "true";
  }
  button.addEventListener("click", () => (timer ? stop() : play()));
  slider.addEventListener("input", () => { stop(); draw(Number(slider.value)); });
  draw(0);
}

document.addEventListener("DOMContentLoaded", async () => {
  try {
    const response = await fetch("/api" + location.pathname, { headers: { Accept: "application/json" } });
    if (!response.ok) throw new Error(`HTTP ${response.status}`);
    const view = await response.json();
    setupFrames(view.pictures.value);
    setupBev(view.motion.value && view.motion.value.bev);
  } catch (err) {
    console.warn("scenario card data", err);
  }
});
