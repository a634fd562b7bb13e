// The robot player: plays the robot's run in 3D from its timed motor commands, at once.
//
// The page gets one JSON document (POST /p/<code>/films/playback, `sim.robot.playback`): the motor
// commands by column (times from the start, joint positions, the gripper's width) and, per part, its
// shapes from the catalog and its pose over time. A troubleshooting episode's document (GET
// /v1/jobs/{id}/playback, `sim.robot_episode_playback`) adds `actions`: the player lists them under
// its controls and marks the one playing, with what it observed once it has been reached. The Panda is pybullet_data's URDF with its light
// (collision) meshes, posed by urdf-loader; the parts are drawn from their shapes. Frames are in the
// simulator's world: metres, z up, quaternions x, y, z, w.
import * as THREE from "three";
import { OBJLoader } from "three/addons/loaders/OBJLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import URDFLoader from "urdf-loader";

const PANDA_URDF = "/web/vendor/franka_panda/panda.urdf";
const PANDA_MESHES = "/web/vendor/franka_panda/meshes";
const WIDTH = 480;
const HEIGHT = 360;

let panda = null;

// The Panda's model, loaded once per page (its meshes are cached by the browser too).
export function loadPanda() {
  if (panda) return panda;
  panda = new Promise(function (resolve, reject) {
    const manager = new THREE.LoadingManager();
    const loader = new URDFLoader(manager);
    let robot = null;
    loader.packages = function () { return PANDA_MESHES; };
    // The visual meshes are 9 MB; the collision meshes (0.4 MB) show the arm as well at this size.
    loader.loadMeshCb = function (path, loading, material, done) {
      new OBJLoader(loading).load(path.replace("/meshes/visual/", "/meshes/collision/"), function (mesh) {
        mesh.traverse(function (child) {
          if (child.isMesh) child.material = new THREE.MeshStandardMaterial({ color: 0xe8e8e8, roughness: 0.6 });
        });
        done(mesh);
      }, undefined, function (error) { done(null, error); });
    };
    manager.onLoad = function () { if (robot) resolve(robot); };
    manager.onError = function (url) { reject(new Error("Could not load " + url)); };
    loader.load(PANDA_URDF, function (model) { robot = model; }, undefined, reject);
  });
  panda.catch(function () { panda = null; }); // a failed load is tried again on the next call
  return panda;
}

function shapeMesh(shape) {
  let geometry;
  if (shape.kind === "box") {
    geometry = new THREE.BoxGeometry(1, 1, 1);
  } else if (shape.kind === "sphere") {
    geometry = new THREE.SphereGeometry(0.5, 24, 16);
  } else {
    geometry = new THREE.CylinderGeometry(0.5, 0.5, 1, 32);
    geometry.rotateX(Math.PI / 2); // the catalog's cylinders stand along z, three.js's along y
  }
  const [r, g, b, a] = shape.color;
  const material = new THREE.MeshStandardMaterial({
    color: new THREE.Color(r, g, b), roughness: 0.5, transparent: a < 1, opacity: a,
  });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.scale.set(shape.size[0], shape.size[1], shape.size[2]);
  mesh.position.set(shape.position[0], shape.position[1], shape.position[2]);
  mesh.rotation.set(shape.rotation[0], shape.rotation[1], shape.rotation[2], "ZYX"); // roll, pitch, yaw
  return mesh;
}

// The index of the last of the sorted `times` at or before `t` (0 before the first).
function before(times, t) {
  let low = 0;
  let high = times.length - 1;
  while (low < high) {
    const middle = (low + high + 1) >> 1;
    if (times[middle] <= t) low = middle; else high = middle - 1;
  }
  return low;
}

function fraction(times, k, t) {
  if (k + 1 >= times.length) return 0;
  const span = times[k + 1] - times[k];
  return span > 0 ? Math.min(1, Math.max(0, (t - times[k]) / span)) : 0;
}

// The list of an episode's actions: `mark(t)` marks those done and the one playing at time `t`, and
// shows what each observed once it is reached; it returns the number of the action playing.
function actionList(run) {
  const names = {};
  run.parts.forEach(function (part) { names[part.id] = part.name; });
  const list = document.createElement("ol");
  list.className = "player-actions";
  list.setAttribute("aria-label", "The robot's actions");
  const items = run.actions.map(function (action) {
    const item = document.createElement("li");
    const what = document.createElement("span");
    what.textContent = action.action + (action.part ? " " + (names[action.part] || action.part) : "");
    const seen = document.createElement("span");
    seen.className = "player-observed";
    const failed = action.passed ? "" : " (the robot could not: " + (action.message || "it stopped") + ")";
    seen.textContent = (action.observed ? ": " + action.observed : "") + failed;
    item.append(what, seen);
    list.append(item);
    return item;
  });
  let shown = null;
  function mark(t) {
    // The action playing is the last that has started: one without motion (inspect, replace) starts
    // where the one before it ended, so it counts as done once the next one moves.
    let current = 0;
    run.actions.forEach(function (action, k) { if (action.start <= t) current = k; });
    if (current === shown) return run.actions[current].number;
    shown = current;
    items.forEach(function (item, k) {
      item.classList.toggle("done", k < current);
      item.classList.toggle("playing", k === current);
      item.querySelector(".player-observed").hidden = k > current;
      if (k === current) item.setAttribute("aria-current", "step"); else item.removeAttribute("aria-current");
    });
    return run.actions[current].number;
  }
  return { list: list, mark: mark };
}

// Build the player in `container` for the run `run`; it starts playing once the Panda is loaded.
export async function createPlayer(container, run) {
  const pointTimes = run.trajectory.times;
  const positions = run.trajectory.positions;
  const widths = run.trajectory.gripper_widths;
  const joints = run.trajectory.joints;
  const fingers = run.trajectory.gripper_joints;
  const seconds = run.seconds;

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f6f8);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, -1.5, 2);
  scene.add(sun);
  const grid = new THREE.GridHelper(2, 20, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);

  const parts = run.parts.map(function (part) {
    const group = new THREE.Group();
    group.name = part.id;
    part.shapes.concat(part.light).forEach(function (shape) { group.add(shapeMesh(shape)); });
    scene.add(group);
    return { id: part.id, group: group, times: part.track.times, poses: part.track.poses };
  });

  const robot = await loadPanda();
  robot.position.set(run.robot.base_position[0], run.robot.base_position[1], run.robot.base_position[2]);
  scene.add(robot);

  const camera = new THREE.PerspectiveCamera(45, WIDTH / HEIGHT, 0.01, 10);
  camera.up.set(0, 0, 1);
  camera.position.set(0.55, -1.55, 1.0);
  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  // As wide as the column (at most WIDTH), in the same proportions: a phone never scrolls sideways.
  function fit() {
    const width = Math.max(160, Math.min(WIDTH, Math.floor(container.clientWidth || WIDTH)));
    renderer.setSize(width, Math.round((width * HEIGHT) / WIDTH));
  }
  fit();
  renderer.domElement.className = "robot-canvas";
  renderer.domElement.setAttribute("role", "img");
  const doing = run.actions ? "repairing" : "assembling";
  renderer.domElement.setAttribute("aria-label", "The robot " + doing + " the " + run.name + " in 3D (drag to turn the view)");
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(-0.25, 0, 0.3);
  controls.update();

  const bar = document.createElement("div");
  bar.className = "player-controls";
  const button = document.createElement("button");
  button.type = "button";
  button.className = "player-play";
  const timeline = document.createElement("input");
  timeline.type = "range";
  timeline.className = "player-timeline";
  timeline.min = "0";
  timeline.max = String(seconds);
  timeline.step = "0.01";
  timeline.setAttribute("aria-label", "Time in the robot's run (seconds)");
  const clock = document.createElement("span");
  clock.className = "small player-clock";
  const speed = document.createElement("select");
  speed.className = "player-speed";
  speed.setAttribute("aria-label", "Playback speed");
  [1, 2, 4].forEach(function (times) { speed.add(new Option(times + "×", String(times))); });
  bar.append(button, timeline, clock, speed);
  container.append(renderer.domElement, bar);
  const steps = run.actions && run.actions.length ? actionList(run) : null;
  if (steps) container.append(steps.list);

  let time = 0;
  let playing = false;
  let frames = 0;
  let last = null;
  let action = null; // the number of the episode's action playing (a troubleshooting run's)
  const posed = {};

  function pose(t) {
    const k = before(pointTimes, t);
    const f = fraction(pointTimes, k, t);
    const next = Math.min(k + 1, pointTimes.length - 1);
    const a = positions[k];
    const b = positions[next];
    joints.forEach(function (name, j) {
      robot.setJointValue(name, a[j] + f * (b[j] - a[j]));
    });
    const width = widths[k] + f * (widths[next] - widths[k]);
    fingers.forEach(function (name) { robot.setJointValue(name, width / 2); }); // each finger opens half
    parts.forEach(function (part) {
      const i = before(part.times, t);
      const g = fraction(part.times, i, t);
      const p = part.poses[i];
      const q = part.poses[Math.min(i + 1, part.poses.length - 1)];
      part.group.position.set(p[0] + g * (q[0] - p[0]), p[1] + g * (q[1] - p[1]), p[2] + g * (q[2] - p[2]));
      part.group.quaternion.set(p[3], p[4], p[5], p[6]).slerp(new THREE.Quaternion(q[3], q[4], q[5], q[6]), g);
      posed[part.id] = part.group.position.toArray().concat(part.group.quaternion.toArray());
    });
  }

  function show() {
    button.textContent = playing ? "Pause" : time >= seconds ? "Play again" : "Play";
    timeline.value = String(time);
    clock.textContent = time.toFixed(1) + " / " + seconds.toFixed(1) + " s";
    if (steps) action = steps.mark(time);
  }

  // Frames are drawn while the run plays, and once after each change while it rests (a paused
  // player leaves the page's processor alone).
  let looping = false;
  let asked = false;

  function draw() {
    pose(time);
    renderer.render(scene, camera);
    frames += 1;
    if (frames === 1) container.dataset.firstFrame = String(performance.now());
    show();
  }

  function frame(now) {
    if (playing && last !== null) {
      time = Math.min(seconds, time + (Number(speed.value) * (now - last)) / 1000);
      if (time >= seconds) playing = false;
    }
    last = now;
    draw();
    if (playing) {
      requestAnimationFrame(frame);
    } else {
      looping = false;
    }
  }

  function play() {
    playing = true;
    show();
    if (looping) return;
    looping = true;
    last = null;
    requestAnimationFrame(frame);
  }

  function redraw() {
    show();
    if (looping || asked) return;
    asked = true;
    requestAnimationFrame(function () {
      asked = false;
      if (!looping) draw();
    });
  }

  button.addEventListener("click", function () {
    if (playing) {
      playing = false;
      show();
      return;
    }
    if (time >= seconds) time = 0;
    play();
  });
  timeline.addEventListener("input", function () {
    time = Number(timeline.value);
    playing = false;
    redraw();
  });
  controls.addEventListener("change", redraw); // the view turned by dragging (a mouse or a finger)
  if (typeof ResizeObserver === "function") {
    let shown = renderer.domElement.width;
    new ResizeObserver(function () {
      fit();
      if (renderer.domElement.width !== shown) {
        shown = renderer.domElement.width;
        redraw();
      }
    }).observe(container);
  }

  const player = {
    // What is shown: the time, whether it plays, frames drawn, every part's pose [x, y, z, qx, qy, qz, qw],
    // and the number of the episode's action playing (null for an assembly).
    state: function () {
      return {
        time: time, seconds: seconds, playing: playing, frames: frames, parts: posed,
        view: camera.position.toArray(), action: action,
      };
    },
    seek: function (t) { time = Math.max(0, Math.min(seconds, t)); playing = false; redraw(); },
    play: play,
    pause: function () { playing = false; show(); },
  };
  container.player = player;
  play();
  return player;
}
