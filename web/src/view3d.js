// pkm report's 3D view: the machine at its pose (joints, struts/links, platform, tool),
// the workspace as a point cloud coloured by the condition number, and the motion of
// the report's path as an animation (path drawn, mechanism moving, time slider,
// actuator values). Reads the scene from <script type="application/json"
// id="pkm-scene">, draws into <div id="pkm-view3d">. Base frame Z up, millimetres.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

const ROLE_COLOURS = {
  BaseJoint: 0x3c3c3c,
  PlatformJoint: 0x2ca02c,
  PlatformCentre: 0x2ca02c,
  Tool: 0xd62728,
  Other: 0x787878,
};
const LINK_STYLE = {
  Strut: { colour: 0x1f77b4, radius: 1.0 },
  Base: { colour: 0x3c3c3c, radius: 0.6 },
  Platform: { colour: 0x2ca02c, radius: 0.6 },
  Tool: { colour: 0xd62728, radius: 1.2 },
  Passive: { colour: 0x969696, radius: 0.8 },
};

/** Blue (well conditioned) to red (badly), for t in [0, 1]. */
function ramp(t) {
  const c = new THREE.Color();
  c.setHSL((1 - Math.min(1, Math.max(0, t))) * 0.66, 0.85, 0.5);
  return c;
}

function setCylinder(mesh, a, b) {
  const dir = new THREE.Vector3().subVectors(b, a);
  const len = dir.length();
  mesh.position.copy(a).addScaledVector(dir, 0.5);
  mesh.scale.set(1, Math.max(len, 1e-9), 1);
  if (len > 0) {
    mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir.divideScalar(len));
  }
}

function start() {
  const host = document.getElementById("pkm-view3d");
  const data = document.getElementById("pkm-scene");
  if (!host || !data) return;
  const scene3 = JSON.parse(data.textContent);
  const sk = scene3.skeleton;
  const view = { ready: false, objects: {}, names: [] };
  window.pkmView = view;

  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    host.textContent = "This browser cannot show the 3D view (no WebGL): " + e.message;
    view.error = String(e.message);
    selfTest({ webgl: false, error: view.error });
    return;
  }
  const width = host.clientWidth || 900;
  const height = 520;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  renderer.setClearColor(0xffffff, 1);
  host.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  view.scene = scene;
  scene.add(new THREE.AmbientLight(0xffffff, 0.65));
  const sun = new THREE.DirectionalLight(0xffffff, 0.9);
  sun.position.set(1, -1.5, 2);
  scene.add(sun);

  // Size of the scene: the skeleton, the cloud and the path.
  const box = new THREE.Box3();
  for (const p of sk.points) box.expandByPoint(new THREE.Vector3(...p.p));
  if (scene3.cloud) {
    const c = scene3.cloud.points;
    for (let i = 0; i < c.length; i += 3) box.expandByPoint(new THREE.Vector3(c[i], c[i + 1], c[i + 2]));
  }
  if (scene3.motion) for (const p of scene3.motion.path) box.expandByPoint(new THREE.Vector3(...p));
  const size = Math.max(box.getSize(new THREE.Vector3()).length(), 1);
  const centre = box.getCenter(new THREE.Vector3());
  const unit = size / 150;

  // The machine: a sphere per point, a cylinder per link.
  const machine = new THREE.Group();
  machine.name = "machine";
  const joints = sk.points.map((p) => {
    const m = new THREE.Mesh(
      new THREE.SphereGeometry(1.6 * unit, 16, 12),
      new THREE.MeshLambertMaterial({ color: ROLE_COLOURS[p.role] ?? 0x787878 })
    );
    m.name = "joint " + p.name;
    m.position.set(...p.p);
    machine.add(m);
    view.names.push(m.name);
    return m;
  });
  const cylinder = new THREE.CylinderGeometry(1, 1, 1, 12);
  const links = sk.links.map((l) => {
    const st = LINK_STYLE[l.kind] ?? LINK_STYLE.Passive;
    const m = new THREE.Mesh(cylinder, new THREE.MeshLambertMaterial({ color: st.colour }));
    m.scale.set(st.radius * unit, 1, st.radius * unit);
    m.name = l.kind.toLowerCase() + " " + sk.points[l.from].name + "-" + sk.points[l.to].name;
    m.userData.radius = st.radius * unit;
    machine.add(m);
    view.names.push(m.name);
    return m;
  });
  const place = (positions) => {
    joints.forEach((j, i) => j.position.set(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]));
    links.forEach((m, k) => {
      const l = sk.links[k];
      setCylinder(m, joints[l.from].position, joints[l.to].position);
      m.scale.x = m.scale.z = m.userData.radius;
    });
  };
  place(sk.points.flatMap((p) => p.p));
  scene.add(machine);
  view.objects.joints = joints.length;
  view.objects.links = links.length;

  // The workspace: reachable points coloured by log10 of the condition number.
  let cloud = null;
  if (scene3.cloud && scene3.cloud.points.length) {
    const c = scene3.cloud;
    const g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(c.points, 3));
    const lo = Math.log10(c.min), hi = Math.log10(Math.max(c.max, c.min * 1.0001));
    const colours = new Float32Array(c.condition.length * 3);
    c.condition.forEach((k, i) => {
      const col = ramp((Math.log10(k) - lo) / (hi - lo));
      colours.set([col.r, col.g, col.b], 3 * i);
    });
    g.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    cloud = new THREE.Points(g, new THREE.PointsMaterial({ size: 0.8 * unit, vertexColors: true, transparent: true, opacity: 0.55 }));
    cloud.name = "workspace";
    scene.add(cloud);
    view.names.push(cloud.name);
    view.objects.cloud = c.condition.length;
  }

  // The path and the animation.
  const m = scene3.motion;
  let path = null;
  if (m && m.path.length > 1) {
    const g = new THREE.BufferGeometry().setFromPoints(m.path.map((p) => new THREE.Vector3(...p)));
    path = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xff7f0e }));
    path.name = "path";
    scene.add(path);
    view.names.push(path.name);
    view.objects.path = m.path.length;
    view.objects.frames = m.frames.length;
  }

  // Axes at the base origin.
  const axes = new THREE.AxesHelper(20 * unit);
  axes.name = "base frame";
  scene.add(axes);

  const camera = new THREE.PerspectiveCamera(40, width / height, size / 1000, size * 20);
  camera.up.set(0, 0, 1);
  // Far enough that the bounding sphere fits the vertical field of view.
  const distance = (0.5 * size) / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2));
  camera.position.copy(centre).add(new THREE.Vector3(0.55, -0.85, 0.45).normalize().multiplyScalar(distance));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  // Controls: layers, and the animation's slider, play button and readout.
  const bar = document.createElement("div");
  bar.className = "view3d-bar";
  const toggle = (label, obj) => {
    if (!obj) return;
    const l = document.createElement("label");
    const cb = document.createElement("input");
    cb.type = "checkbox";
    cb.checked = true;
    cb.onchange = () => { obj.visible = cb.checked; };
    l.append(cb, " " + label + " ");
    bar.append(l);
  };
  toggle("workspace", cloud);
  toggle("path", path);
  let frame = 0, playing = false;
  const readout = document.createElement("div");
  readout.className = "view3d-readout";
  const show = (i) => {
    if (!m || !m.frames.length) return;
    frame = Math.max(0, Math.min(m.frames.length - 1, i));
    place(m.frames[frame]);
    const vals = m.actuators.map((a) => `${a.name} ${a.values[frame].toFixed(3)} ${a.unit}`);
    readout.textContent = `t = ${m.t[frame].toFixed(3)} s   ` + vals.join("   ");
    slider.value = String(frame);
  };
  let slider = null;
  if (m && m.frames.length) {
    const play = document.createElement("button");
    play.textContent = "▶ play";
    play.onclick = () => { playing = !playing; play.textContent = playing ? "❚❚ pause" : "▶ play"; };
    slider = document.createElement("input");
    slider.type = "range";
    slider.min = "0";
    slider.max = String(m.frames.length - 1);
    slider.value = "0";
    slider.style.width = "50%";
    slider.oninput = () => { playing = false; play.textContent = "▶ play"; show(Number(slider.value)); };
    bar.append(play, " time ", slider);
  }
  host.append(bar, readout);
  view.frame = show;

  // Follow the page's width (a scrollbar appearing after load, a resized window).
  const fit = () => {
    const w = host.clientWidth || width;
    if (Math.abs(w - renderer.domElement.clientWidth) > 1) {
      renderer.setSize(w, height);
      camera.aspect = w / height;
      camera.updateProjectionMatrix();
    }
  };
  window.addEventListener("resize", fit);
  fit();

  let last = 0;
  const loop = (now) => {
    if (playing && m && m.frames.length && now - last > 40) {
      last = now;
      show((frame + 1) % m.frames.length);
    }
    controls.update();
    renderer.render(scene, camera);
    requestAnimationFrame(loop);
  };
  renderer.render(scene, camera);
  view.ready = true;
  view.renderer = renderer;
  if (location.hash === "#selftest") {
    // What a browser test checks: the canvas is not blank (pixels drawn into a 2D
    // canvas), the animation moves the machine, and the objects are there.
    if (m && m.frames.length) show(Math.floor(m.frames.length / 2));
    // The share of the canvas drawn (not white) and the colours used, sampled at
    // 200 x 120: with everything shown, then with the machine alone.
    const sample = () => {
      renderer.render(scene, camera);
      const c = document.createElement("canvas");
      c.width = 200;
      c.height = 120;
      const g = c.getContext("2d");
      g.drawImage(renderer.domElement, 0, 0, 200, 120);
      const px = g.getImageData(0, 0, 200, 120).data;
      let drawn = 0;
      const colours = new Set();
      for (let i = 0; i < px.length; i += 4) {
        if (px[i] < 245 || px[i + 1] < 245 || px[i + 2] < 245) drawn++;
        colours.add(((px[i] >> 3) << 10) | ((px[i + 1] >> 3) << 5) | (px[i + 2] >> 3));
      }
      return { drawn: drawn / (200 * 120), colours: colours.size };
    };
    const all = sample();
    const layers = [cloud, path, axes].filter(Boolean);
    layers.forEach((o) => { o.visible = false; });
    const alone = sample();
    layers.forEach((o) => { o.visible = true; });
    renderer.render(scene, camera);
    selfTest({
      webgl: true,
      objects: view.objects,
      names: view.names,
      drawn: all.drawn,
      colours: all.colours,
      machine_drawn: alone.drawn,
      readout: readout.textContent,
    });
  }
  requestAnimationFrame(loop);
}

/** Writes the self-test's findings and the page's errors into <pre id="pkm-selftest">. */
function selfTest(found) {
  if (location.hash !== "#selftest") return;
  const pre = document.createElement("pre");
  pre.id = "pkm-selftest";
  pre.textContent = JSON.stringify({ ...found, errors: window.pkmErrors || [] });
  document.body.append(pre);
}

if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
else start();
