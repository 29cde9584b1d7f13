// The plamo replay viewer. `plamo view` inlines this bundle, the run's replay.glb
// (base64) and overlay data as `window.PLAMO_DATA = { runs: [...] }` into one page.
// Everything lives in the simulation's Z-up metres inside `world` (rotated to
// three.js's Y-up), exactly like the glTF's root node.
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { Line2 } from "three/examples/jsm/lines/Line2.js";
import { LineMaterial } from "three/examples/jsm/lines/LineMaterial.js";
import { LineGeometry } from "three/examples/jsm/lines/LineGeometry.js";

const DATA = window.PLAMO_DATA;
const SPEED_MAX = 3.0; // m/s at the red end of the speed colours (as run.png)
const RUN_COLORS = ["#ff3da5", "#00c8ff", "#ffd000", "#9dff00"];

const css = `
html, body { margin: 0; height: 100%; overflow: hidden; background: #9cc3e6;
  font: 14px/1.35 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #eee; }
canvas { display: block; }
.panel { position: absolute; z-index: 2; background: rgba(18, 22, 30, 0.85); border-radius: 8px;
  padding: 10px 14px; box-shadow: 0 2px 10px rgba(0,0,0,.3); }
#hud { top: 12px; left: 12px; min-width: 300px; max-width: 440px; }
#hud h1 { font-size: 15px; margin: 0 0 6px 0; font-weight: 600; }
#hud .run { margin-top: 8px; border-left: 4px solid; padding-left: 8px; }
#hud .instr { font-weight: 600; color: #fff; }
#hud table { border-collapse: collapse; margin-top: 2px; }
#hud td { padding: 0 12px 0 0; white-space: nowrap; }
#hud td.v { font-variant-numeric: tabular-nums; text-align: right; color: #fff; }
#hud .fallen { color: #ff6b6b; font-weight: 700; }
#time { font-size: 20px; font-variant-numeric: tabular-nums; color: #fff; }
#controls { left: 12px; right: 12px; bottom: 12px; display: flex; gap: 10px; align-items: center; }
#controls button, #controls select { background: #2d3646; color: #eee; border: 1px solid #4a566b;
  border-radius: 5px; padding: 5px 10px; font: inherit; cursor: pointer; }
#controls button.on { background: #3d6fd6; border-color: #5b8cf0; }
#play { min-width: 78px; }
#scrub { flex: 1; accent-color: #5b8cf0; }
#clock { font-variant-numeric: tabular-nums; min-width: 130px; text-align: right; }
#legend { right: 12px; top: 12px; width: 220px; font-size: 12px; }
#legend .bar { height: 10px; border-radius: 3px; margin: 4px 0 2px 0;
  background: linear-gradient(90deg, #1e3cdc, #14aac8, #28aa3c, #f0b414, #d71e1e); }
#legend .row { display: flex; justify-content: space-between; }
#legend .swatch { display: inline-block; width: 18px; height: 4px; vertical-align: middle; margin-right: 6px; }
#help { color: #aab; font-size: 11px; margin-top: 6px; }
.label { position: absolute; z-index: 1; transform: translate(-50%, -100%); pointer-events: none;
  background: rgba(255, 140, 20, 0.92); color: #201000; padding: 1px 6px; border-radius: 4px;
  font-size: 12px; font-weight: 600; white-space: nowrap; }
#error { position: absolute; inset: 0; display: none; padding: 40px; background: #300; color: #fff; }
`;

function el(tag, attrs = {}, parent = document.body) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") e.textContent = v;
    else if (k === "html") e.innerHTML = v;
    else e.setAttribute(k, v);
  }
  parent.appendChild(e);
  return e;
}

function escapeHtml(s) {
  return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
}

// Blue at rest to red at SPEED_MAX, the same five stops as run.png's colour bar.
const STOPS = [[30, 60, 220], [20, 170, 200], [40, 170, 60], [240, 180, 20], [215, 30, 30]];
function speedColor(v) {
  const f = Math.min(Math.max(v / SPEED_MAX, 0), 1) * (STOPS.length - 1);
  const i = Math.min(Math.floor(f), STOPS.length - 2);
  const w = f - i;
  return STOPS[i].map((c, k) => (c + w * (STOPS[i + 1][k] - c)) / 255);
}

function base64ToBuffer(b64) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}

function fatLine(points, colors, width, resolution, opts = {}) {
  const geo = new LineGeometry();
  geo.setPositions(points.flat());
  if (colors) geo.setColors(colors.flat());
  const mat = new LineMaterial({
    color: colors ? 0xffffff : opts.color ?? 0xffffff,
    vertexColors: !!colors,
    linewidth: width,
    transparent: !!opts.opacity,
    opacity: opts.opacity ?? 1,
    dashed: false,
  });
  mat.resolution.copy(resolution);
  const line = new Line2(geo, mat);
  line.computeLineDistances();
  return line;
}

function fmt(v, digits = 2) {
  return v === null || v === undefined || Number.isNaN(v) ? "–" : v.toFixed(digits);
}

async function main() {
  el("style", { text: css }, document.head);
  const errorBox = el("div", { id: "error" });
  if (!DATA || !DATA.runs || DATA.runs.length === 0) {
    errorBox.style.display = "block";
    errorBox.textContent = "No run data in this page (write it with `plamo view DIR`).";
    return;
  }

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFSoftShadowMap;
  document.body.appendChild(renderer.domElement);
  const resolution = new THREE.Vector2(window.innerWidth, window.innerHeight);

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x9cc3e6);
  scene.fog = new THREE.Fog(0x9cc3e6, 60, 140);
  scene.add(new THREE.HemisphereLight(0xdfefff, 0x4a5a3a, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 2.2);
  sun.castShadow = true;
  sun.shadow.mapSize.set(2048, 2048);
  Object.assign(sun.shadow.camera, { left: -12, right: 12, top: 12, bottom: -12, near: 1, far: 80 });
  sun.shadow.bias = -0.0005;
  scene.add(sun, sun.target);

  const world = new THREE.Group(); // Z-up, like the glTF's root node
  world.rotation.x = -Math.PI / 2;
  scene.add(world);

  const camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.05, 400);
  camera.up.set(0, 1, 0);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.enableDamping = true;
  controls.maxPolarAngle = Math.PI * 0.495;
  controls.maxDistance = 90;

  // Z-up world coordinates to three.js scene coordinates.
  const toScene = (p) => new THREE.Vector3(p[0], p[2], -p[1]);

  const loader = new GLTFLoader();
  const runs = [];
  let pathCount = 0;
  for (const [r, run] of DATA.runs.entries()) {
    const gltf = await new Promise((ok, fail) => loader.parse(base64ToBuffer(run.glb), "", ok, fail));
    const root = gltf.scene;
    root.traverse((o) => {
      if (o.isMesh) {
        o.castShadow = true;
        o.receiveShadow = true;
      }
    });
    // The HTML labels name the landmarks here; the glTF's marker pins (for other
    // glTF viewers) would only stand in the way of the follow camera.
    const markers = [];
    root.traverse((o) => {
      if (/marker$/.test(o.name)) markers.push(o);
    });
    for (const m of markers) m.visible = false;
    if (r > 0) {
      // Later runs share the scene: show only their humanoids, tinted in the run's colour.
      const keep = new Set();
      root.traverse((o) => {
        if (o.userData.agent !== undefined) o.traverse((c) => keep.add(c));
      });
      root.traverse((o) => {
        if (o.isMesh && !keep.has(o)) o.visible = false;
        if (o.isMesh && keep.has(o)) {
          o.material = o.material.clone();
          o.material.color.lerp(new THREE.Color(RUN_COLORS[r % RUN_COLORS.length]), 0.6);
        }
      });
    }
    scene.add(root);
    const mixer = new THREE.AnimationMixer(root);
    const clip = gltf.animations[0];
    let duration = 0;
    if (clip) {
      const action = mixer.clipAction(clip);
      action.setLoop(THREE.LoopOnce, 1);
      action.clampWhenFinished = true;
      action.play();
      duration = clip.duration;
    }
    const agents = run.agents.map((a, k) => {
      // GLTFLoader rewrites node names (spaces), so find the agent by its extras.
      let group = null;
      root.traverse((o) => {
        if (o.userData.agent === k) group = o;
      });
      // The pelvis is the agent node's only child (names repeat across agents, and
      // GLTFLoader makes them unique with suffixes).
      const pelvis = group ? group.children[0] ?? null : null;
      // Planned head path, coloured by planned speed, one polyline per instruction.
      for (const seg of a.plan) {
        if (seg.length < 2) continue;
        const pts = seg.map((p) => [p[0], p[1], p[2]]);
        const cols = seg.map((p) => speedColor(p[3]));
        const line = fatLine(pts, cols, 5, resolution);
        world.add(line);
      }
      // Executed head path, drawn up to the current time, one colour per humanoid
      // across all runs (a 2-agent run must not draw both paths alike).
      const color = RUN_COLORS[pathCount++ % RUN_COLORS.length];
      let executed = null;
      if (a.head.length >= 2) {
        executed = fatLine(a.head, null, 3, resolution, { color });
        world.add(executed);
      }
      return { data: a, pelvis, executed, color };
    });
    runs.push({ run, mixer, duration, agents, color: agents[0]?.color ?? RUN_COLORS[0] });
  }
  const duration = Math.max(...runs.map((r) => r.duration), 0);

  // Landmark names, positioned over their markers every frame.
  const labels = DATA.runs[0].landmarks.map((l) => ({
    pos: toScene([l.pos[0], l.pos[1], l.pos[2] + 2.3]),
    div: el("div", { class: "label", text: l.name }),
  }));

  // Overlay.
  const hud = el("div", { id: "hud", class: "panel" });
  const first = DATA.runs[0];
  el("h1", { text: `plamo replay · ${first.scene}` }, hud);
  const timeEl = el("div", { id: "time", text: "t = 0.00 s" }, hud);
  const runEls = runs.map((r) => {
    const box = el("div", { class: "run" }, hud);
    box.style.borderColor = r.color;
    return box;
  });
  const legend = el("div", { id: "legend", class: "panel" });
  legend.innerHTML = `<div>planned path, colour = planned speed</div><div class="bar"></div>
    <div class="row"><span>0</span><span>1.5</span><span>${SPEED_MAX} m/s</span></div>
    ${runs
      .flatMap((r) =>
        r.agents.map(
          (a, k) =>
            `<div><span class="swatch" style="background:${a.color}"></span>executed head path · ${escapeHtml(r.run.physics)} (${escapeHtml(r.run.name)})${r.agents.length > 1 ? ` · humanoid ${k}` : ""}</div>`,
        ),
      )
      .join("")}
    <div id="help">drag: orbit · wheel: zoom · right-drag: pan<br>space: play/pause · F: follow · ←/→: step</div>`;

  const bar = el("div", { id: "controls", class: "panel" });
  const playBtn = el("button", { id: "play", text: "▶ Play" }, bar);
  const speedSel = el("select", { id: "speed", title: "playback speed" }, bar);
  for (const s of [0.1, 0.25, 0.5, 1, 2, 4]) {
    const o = el("option", { value: String(s), text: `${s}×` }, speedSel);
    if (s === 1) o.selected = true;
  }
  const scrub = el("input", { id: "scrub", type: "range", min: "0", max: String(duration), step: "0.001", value: "0" }, bar);
  const clock = el("span", { id: "clock" }, bar);
  const followBtn = el("button", { id: "follow", class: "on", text: "Follow" }, bar);
  // Whom the follow camera follows, when there is more than one humanoid.
  const targets = runs.flatMap((r, ri) =>
    r.agents
      .filter((a) => a.pelvis)
      .map((a, k) => ({ pelvis: a.pelvis, label: `${r.run.physics}${runs.length > 1 ? ` (${r.run.name})` : ""} · agent ${k}` }))
  );
  let followed = targets[0]?.pelvis;
  if (targets.length > 1) {
    const sel = el("select", { id: "target", title: "humanoid to follow" }, bar);
    targets.forEach((t, i) => el("option", { value: String(i), text: t.label }, sel));
    sel.onchange = () => {
      followed = targets[Number(sel.value)].pelvis;
      setFollow(true);
    };
  }
  const orbitBtn = el("button", { id: "orbit", text: "Free orbit" }, bar);

  let time = 0;
  let playing = false;
  let follow = true;
  const setPlaying = (p) => {
    playing = p;
    if (playing && time >= duration) time = 0;
    playBtn.textContent = playing ? "❚❚ Pause" : "▶ Play";
  };
  const setFollow = (f) => {
    follow = f;
    followBtn.classList.toggle("on", f);
    orbitBtn.classList.toggle("on", !f);
  };
  playBtn.onclick = () => setPlaying(!playing);
  followBtn.onclick = () => setFollow(true);
  orbitBtn.onclick = () => setFollow(false);
  scrub.oninput = () => {
    time = Number(scrub.value);
  };
  window.addEventListener("keydown", (e) => {
    if (e.target.tagName === "SELECT") return;
    if (e.code === "Space") {
      setPlaying(!playing);
      e.preventDefault();
    } else if (e.key === "f" || e.key === "F") setFollow(!follow);
    else if (e.key === "ArrowRight") time = Math.min(duration, time + 1 / 30);
    else if (e.key === "ArrowLeft") time = Math.max(0, time - 1 / 30);
  });

  // Start behind and above the first humanoid, looking along its first path.
  const focus = new THREE.Vector3();
  const firstPelvis = followed;
  runs.forEach((r) => r.mixer.setTime(0));
  scene.updateMatrixWorld(true);
  if (firstPelvis) firstPelvis.getWorldPosition(focus);
  const plan0 = first.agents[0]?.plan?.[0] ?? [];
  const ahead = plan0.length > 5 ? toScene(plan0[Math.min(25, plan0.length - 1)]) : focus.clone().add(new THREE.Vector3(1, 0, 0));
  const dir = ahead.clone().sub(focus).setY(0).normalize();
  camera.position.copy(focus).addScaledVector(dir, -6.5).add(new THREE.Vector3(0, 3.6, 0));
  controls.target.copy(focus);
  const lastFocus = focus.clone();

  function frameIndex(t, ts) {
    // Last recorded frame at or before t.
    let lo = 0;
    let hi = ts.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (ts[mid] <= t + 1e-6) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  function updateHud() {
    timeEl.textContent = `t = ${time.toFixed(2)} s`;
    clock.textContent = `${time.toFixed(2)} / ${duration.toFixed(2)} s`;
    runs.forEach((r, ri) => {
      const parts = [`<div>${escapeHtml(r.run.physics)} · ${escapeHtml(r.run.status)}${runs.length > 1 ? ` · ${escapeHtml(r.run.name)}` : ""}</div>`];
      for (const [k, a] of r.agents.entries()) {
        const d = a.data;
        const i = frameIndex(time, d.t);
        const n = d.instructions.length;
        const ins = Math.min(d.instruction[i], n - 1);
        parts.push(
          `<div class="instr">${r.agents.length > 1 ? `agent ${k}: ` : ""}${ins + 1}/${n} “${escapeHtml(d.instructions[ins] ?? "")}”</div>` +
            `<table><tr><td>speed</td><td class="v">${fmt(d.speed[i])} m/s</td><td>plan</td><td class="v">${fmt(d.plan_speed[i])} m/s</td></tr>` +
            `<tr><td>head height</td><td class="v">${fmt(d.head_height[i])} m</td><td>XY error</td><td class="v">${fmt(d.xy_err[i])} m</td></tr></table>` +
            (d.fallen[i] ? `<div class="fallen">fallen</div>` : "")
        );
        if (a.executed) a.executed.geometry.instanceCount = Math.max(i, 0);
      }
      runEls[ri].innerHTML = parts.join("");
    });
  }

  function resize() {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    resolution.set(window.innerWidth, window.innerHeight);
    world.traverse((o) => {
      if (o.material && o.material.resolution) o.material.resolution.copy(resolution);
    });
  }
  window.addEventListener("resize", resize);

  const tmp = new THREE.Vector3();
  let last = performance.now();
  let hudTime = -1;
  function animate(now) {
    const dt = Math.min((now - last) / 1000, 0.1);
    last = now;
    if (playing) {
      time += dt * Number(speedSel.value);
      if (time >= duration) {
        time = duration;
        setPlaying(false);
      }
      scrub.value = String(time);
    }
    for (const r of runs) r.mixer.setTime(Math.min(time, Math.max(r.duration - 1e-6, 0)));
    scene.updateMatrixWorld();
    if (followed) {
      // Glide after the pelvis (no step bobbing or jumps when scrubbing); the camera
      // keeps its offset, so orbiting and zooming still work while following.
      followed.getWorldPosition(tmp);
      const next = lastFocus.clone().lerp(tmp, 1 - Math.exp(-6 * dt));
      if (follow) {
        const d = next.clone().sub(lastFocus);
        camera.position.add(d);
        controls.target.add(d);
      }
      lastFocus.copy(next);
      sun.position.copy(tmp).add(new THREE.Vector3(-8, 18, 6));
      sun.target.position.copy(tmp);
    }
    controls.update();
    for (const l of labels) {
      tmp.copy(l.pos).project(camera);
      const visible = tmp.z < 1 && Math.abs(tmp.x) < 1.1 && Math.abs(tmp.y) < 1.1;
      l.div.style.display = visible ? "block" : "none";
      if (visible) {
        l.div.style.left = `${((tmp.x + 1) / 2) * window.innerWidth}px`;
        l.div.style.top = `${((1 - tmp.y) / 2) * window.innerHeight}px`;
      }
    }
    if (time !== hudTime) {
      hudTime = time;
      updateHud();
    }
    renderer.render(scene, camera);
    requestAnimationFrame(animate);
  }
  updateHud();
  requestAnimationFrame(animate);

  // For scripted use (the browser test): the state behind the page.
  window.plamoViewer = {
    get time() {
      return time;
    },
    get playing() {
      return playing;
    },
    duration,
    ready: true,
  };
}

main().catch((e) => {
  const box = document.getElementById("error") || document.body.appendChild(document.createElement("div"));
  box.id = "error";
  box.style.display = "block";
  box.textContent = `The viewer failed: ${e && e.stack ? e.stack : e}`;
  console.error(e);
});
