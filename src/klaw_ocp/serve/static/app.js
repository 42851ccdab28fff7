// The playground's page: the panel, the websocket and the playback. The server sends each step
// with its frames when the page asks for it, which it does shortly before the step on screen ends
// (needBeforeEnd: a few times the server's recent delivery time): the next step is ready in time,
// and a change made before then reaches the walk one step earlier than if it were asked for at
// the start of the step (docs/serve.md).
import { framePoints } from "./kinematics.js";
import { Scene } from "./scene.js";
import { Strips } from "./strips.js";

const $ = (id) => document.getElementById(id);
const scene = new Scene($("scene"));
const strips = new Strips($("strip-hip"), $("strip-torque"), $("strip-gait"), $("legend"));
// how long before the step on screen ends the page asks for the next: NEED_MARGIN times the
// slowest of the last NEED_HISTORY deliveries (ask to step received), within these bounds. The
// later it asks, the later a change still reaches the step after the next; the server solves a
// step in 10-20 ms, and a step lasts 0.35 s or more
const NEED_BEFORE_END_MAX_S = 0.25, NEED_BEFORE_END_MIN_S = 0.06, NEED_MARGIN = 4, NEED_HISTORY = 8;
let deliveries = [], askedAt = null;
function needBeforeEnd() {
  if (deliveries.length === 0) return NEED_BEFORE_END_MAX_S;
  return Math.min(NEED_BEFORE_END_MAX_S, Math.max(NEED_BEFORE_END_MIN_S, NEED_MARGIN * Math.max(...deliveries)));
}
const SEND_EVERY_MS = 150;     // a dragged slider sends at most this often (the server's rate limit is higher)
const ATTRIBUTE_LABELS = { pelvic_list: "pelvic list", pelvic_rotation: "pelvic rotation",
                           arm_swing_amplitude: "arm swing", toe_clearance: "toe clearance" };

// what the browser test reads: the steps shown, each with its cadence, the last step received
// (with the points the page made of it), and the page's forward kinematics
const state = window.klaw = { shown: [], planned: [], ended: false, connected: false, refusals: [], accepted: null,
                              exports: [] };
window.klawForwardKinematics = framePoints;
let socket, skeleton = null, steps = new Map(), current = null, walkTime = 0, lastTick = null, walkEnded = false, asked = 0;

function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

// -- the panel ---------------------------------------------------------------------------------
function showValue(input) {
  input.closest("label").querySelector("output").textContent =
    Number(input.value).toFixed(input.step < 0.1 ? 3 : input.step < 1 ? 2 : 0);
}

// each slider's value in the walk going on, by its field ("walk.speed", "attributes.pelvic_list"):
// a refused value puts its slider back there, beside the refusal, so the panel shows the walk
const inEffect = new Map();
function sliderOf(field) { return document.querySelector(`.control[data-field="${field}"] input[type=range]`); }
function takeAllSliders() {
  for (const input of document.querySelectorAll(".control[data-field] input[type=range]")) {
    inEffect.set(input.closest(".control").dataset.field, Number(input.value));
  }
}

function setUpSlider(input, spec) {
  input.min = spec.min; input.max = spec.max; input.value = spec.value;
  input.addEventListener("input", () => showValue(input));
  showValue(input);
  inEffect.set(input.closest(".control").dataset.field, Number(spec.value));
  const allowed = input.closest(".control").querySelector(".allowed") || document.createElement("span");
  allowed.className = "allowed note";
  allowed.textContent = ` (supported ${spec.allowed[0].toFixed(2)} – ${spec.allowed[1].toFixed(2)} ${spec.unit})`;
  input.closest("label").insertBefore(allowed, input);
}

function secondParameter() { return document.querySelector("input[name=second]:checked").value; }

function locomotion() {
  const values = { speed: Number($("speed").value) };
  const second = secondParameter();
  if (second !== "none") values[second] = Number($(second).value);
  return values;
}

function settings() {
  const out = { "walk.start_from_rest": $("start_from_rest").checked, "solver.method": $("method").value };
  for (const input of document.querySelectorAll("input[type=range][data-setting]")) out[input.dataset.setting] = Number(input.value);
  for (const [key, value] of Object.entries(locomotion())) out[`walk.${key}`] = value;
  return out;
}

function clearRefusals() { for (const p of document.querySelectorAll(".refusal")) p.textContent = ""; }

function showRefusal(field, message) {
  state.refusals.push({ field, message });
  // "walk.step[3].step_length" is the step-length slider's, "attributes.x" the attribute's
  const key = field.replace(/^walk\.step\[\d+\]\./, "walk.").replace(/^walk\.schedule\[\d+\]\./, "walk.");
  const control = document.querySelector(`.control[data-field="${key}"]`);
  const target = control ? control.querySelector(".refusal") : $("refusal-general");
  target.textContent = message;
  const slider = sliderOf(key);
  if (slider && inEffect.has(key)) { slider.value = inEffect.get(key); showValue(slider); }
}

let pending = null, lastSent = 0;
function sendLocomotion() {
  // throttled: the first move is sent at once, then at most every SEND_EVERY_MS, and the last
  // position of a dragged slider always
  const wait = lastSent + SEND_EVERY_MS - performance.now();
  if (pending) return;
  pending = setTimeout(() => { pending = null; lastSent = performance.now(); send({ type: "set", values: locomotion() }); },
                       Math.max(wait, 0));
}

function updateSecond() {
  for (const name of ["step_length", "step_frequency"]) {
    $(name).closest(".control").classList.toggle("disabled", secondParameter() !== name);
  }
}

async function setUpPanel() {
  const info = await (await fetch("/info")).json();
  const e = info.envelope;
  for (const name of ["speed", "step_length", "step_frequency", "height", "mass"]) setUpSlider($(name), e[name]);
  for (const [name, spec] of Object.entries(e.attributes)) {
    const div = document.createElement("div");
    div.className = "control"; div.dataset.field = `attributes.${name}`;
    div.innerHTML = `<label>${ATTRIBUTE_LABELS[name]} <output></output> ${spec.unit}
      <input type="range" id="attr-${name}" step="${spec.unit === "m" ? 0.001 : 0.5}" data-setting="attributes.${name}" data-per-step></label>
      <p class="refusal"></p>`;
    $("attributes").appendChild(div);
    setUpSlider(div.querySelector("input"), spec);
  }
  $("method").innerHTML = e.methods.map((m) => `<option ${m === e.method ? "selected" : ""}>${m}</option>`).join("");
  $("start_from_rest").checked = e.start_from_rest;
  for (const name of ["speed", "step_length", "step_frequency"]) $(name).addEventListener("input", sendLocomotion);
  for (const radio of document.querySelectorAll("input[name=second]")) {
    radio.addEventListener("change", () => { updateSecond(); sendLocomotion(); });
  }
  updateSecond();
  // the determinants change the walk from the next step that can change, as the locomotion
  // parameters do; the walker's other settings (body, solver, start) make a new walk, which
  // starts with the determinants as they are then
  for (const input of document.querySelectorAll("[data-setting]")) {
    if (input.hasAttribute("data-per-step")) {
      input.addEventListener("change", () => send({ type: "set", values: { [input.dataset.setting]: Number(input.value) } }));
    } else {
      input.addEventListener("change", () => send({ type: "start", settings: settings() }));
    }
  }
  $("start").addEventListener("click", () => send({ type: "start", settings: settings() }));
  $("stop").addEventListener("click", () => send({ type: "stop" }));
  $("download-bvh").addEventListener("click", () => { wanted.push("bvh"); send({ type: "export" }); });
  $("download-config").addEventListener("click", () => { wanted.push("config"); send({ type: "export" }); });
}

// the files asked for, in order: the server answers one socket's exports in the order asked
const wanted = [];
function download(name, text, type) {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = Object.assign(document.createElement("a"), { href: url, download: name });
  document.body.appendChild(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

// -- the socket --------------------------------------------------------------------------------
function connect() {
  socket = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/walk`);
  socket.onopen = () => { state.connected = true; $("status").textContent = "connected"; };
  socket.onclose = (event) => {
    state.connected = false;
    $("status").textContent = `disconnected${event.reason ? ": " + event.reason : ""}`;
  };
  socket.onmessage = (event) => receive(JSON.parse(event.data));
}

function receive(m) {
  if (m.type === "skeleton") {
    skeleton = m; scene.setSkeleton(m); strips.reset(); steps = new Map(); current = null; walkTime = 0; asked = 0; askedAt = null;
    walkEnded = false; state.ended = false; state.shown = []; state.planned = [];
    clearRefusals();
    takeAllSliders();        // the new walk's settings are the panel's
    $("download-bvh").disabled = $("download-config").disabled = true;
    $("status").textContent = `walking (${m.method}${m.start_from_rest ? ", from rest" : ""})`;
  } else if (m.type === "step") {
    // each frame's root position and 56 angles, exactly (base64 of float64s): the joints' and end
    // sites' positions made here, as the server's forward kinematics makes them (kinematics.js)
    m.frames.points = framePoints(skeleton, m.frames);
    steps.set(m.index, m); state.last_step = m;
    if (askedAt !== null && m.index === asked) {      // (steps 0 and 1 come unasked)
      deliveries = [...deliveries, (performance.now() - askedAt) / 1000].slice(-NEED_HISTORY);
      askedAt = null;
      state.need_before_end_s = needBeforeEnd();
    }
    $("download-bvh").disabled = $("download-config").disabled = false;    // the walk so far
    $("planned-step").textContent = m.planned.step;
    state.planned.push(m.planned);
    $("planned-cadence").textContent = m.planned.step_frequency.toFixed(1);
    $("solve-ms").textContent = m.solve_ms.toFixed(1);
  } else if (m.type === "refused") {
    showRefusal(m.field, m.message);
  } else if (m.type === "accepted") {
    state.accepted = { on_screen: current ? current.index : null, target: m.target };
    for (const key of ["speed", "step_length", "step_frequency"]) {
      const p = document.querySelector(`.control[data-field="walk.${key}"] .refusal`);
      if (p && key in m.target) { p.textContent = ""; inEffect.set(`walk.${key}`, m.target[key]); }
    }
    for (const [name, value] of Object.entries(m.target.attributes || {})) {
      const p = document.querySelector(`.control[data-field="attributes.${name}"] .refusal`);
      if (p) p.textContent = "";
      if (typeof value === "number") inEffect.set(`attributes.${name}`, value);
    }
  } else if (m.type === "stopping") {
    $("status").textContent = "stopping at rest…";
  } else if (m.type === "ended") {
    walkEnded = true;
  } else if (m.type === "failed") {
    walkEnded = true; showRefusal("message", m.message);
  } else if (m.type === "export") {
    const file = wanted.shift() || "bvh";
    state.exported = { file, steps: m.steps, bvh_chars: m.bvh.length, config_chars: m.config.length };
    state.exports.push(state.exported);
    if (file === "bvh") download("walk.bvh", m.bvh, "text/plain");
    else download(`${m.name}.yaml`, m.config, "application/yaml");
  }
}

// -- playback ----------------------------------------------------------------------------------
function begin(step) {
  current = step;
  state.shown.push({ index: step.index, step_frequency: step.step_frequency, speed: step.speed,
                     pelvic_list: step.attributes.pelvic_list });
  scene.addFootprint(step.foot, step.stance_leg);
  strips.add(step);
  $("step").textContent = step.index + (step.closing ? " (closing)" : "");
  $("cadence").textContent = step.step_frequency.toFixed(1);
  $("speed-now").textContent = step.speed.toFixed(2);
}

function tick(now) {
  requestAnimationFrame(tick);
  const dt = lastTick === null ? 0 : Math.min((now - lastTick) / 1000, 0.1);
  lastTick = now;
  if (current === null) {
    if (steps.has(0)) { begin(steps.get(0)); walkTime = current.t_start; }
  } else {
    walkTime += dt;
    const end = current.t_start + current.t_step;
    if (!current.closing && asked <= current.index && walkTime >= end - needBeforeEnd()) {
      asked = current.index + 1;
      askedAt = performance.now();
      send({ type: "need", step: asked });
    }
    if (walkTime >= end) {
      const next = steps.get(current.index + 1);
      if (next) { steps.delete(current.index - 2); begin(next); }
      else {
        walkTime = end;      // the next step is not here yet (or the walk ended): hold the last frame
        if (walkEnded && !state.ended) { state.ended = true; $("status").textContent = "at rest: the walk ended"; }
      }
    }
  }
  if (current) {
    const t = current.frames.t;
    let i = 0;
    while (i + 1 < t.length && t[i + 1] <= walkTime) i++;
    if (t.length) scene.pose(current.frames.points[i]);
    strips.draw(walkTime);
  }
  scene.follow = $("follow").checked;
  scene.render();
}

setUpPanel().then(connect);
requestAnimationFrame(tick);
