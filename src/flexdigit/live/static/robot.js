// A tendon robot's motion in 3D (flexdigit live --robot): the backbone and tendons as lines, three.js vendored
// into the package (make three), the motion from /motion.json (metres, the base frame: z along the backbone).
import * as THREE from "/static/vendor/three.module.js";

const info = document.getElementById("info");
const canvas = document.getElementById("view");
const state = { ready: false, frame: 0, frames: 0, points: 0, error: null };
window.flexdigitRobot = state;

function line(points, color) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(points.length * 3), 3));
  const object = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color }));
  object.frustumCulled = false;
  return object;
}

function place(object, points) {
  const array = object.geometry.attributes.position.array;
  points.forEach((p, i) => array.set(p, 3 * i));
  object.geometry.attributes.position.needsUpdate = true;
}

async function main() {
  const motion = await (await fetch("/motion.json")).json();
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true });
  const scene = new THREE.Scene();
  scene.up = new THREE.Vector3(0, 0, 1);
  const length = motion.length_m;
  const camera = new THREE.PerspectiveCamera(45, 1, length / 100, length * 20);
  camera.up.set(0, 0, 1);
  camera.position.set(1.6 * length, -1.6 * length, 0.9 * length);
  camera.lookAt(0, 0, 0.5 * length);
  scene.add(new THREE.GridHelper(length, 10, 0x444444, 0x333333).rotateX(Math.PI / 2));
  const backbone = line(motion.backbone_m[0], 0xe0e0e0);
  const tendons = motion.tendons_m[0].map((points) => line(points, 0xd08030));
  scene.add(backbone, ...tendons);
  state.frames = motion.t_s.length;
  state.points = motion.backbone_m[0].length;
  const start = performance.now();
  function draw() {
    const t = (performance.now() - start) / 1000;
    let k = motion.t_s.findIndex((s) => s > t);
    k = k < 0 ? motion.t_s.length - 1 : Math.max(k - 1, 0);
    state.frame = k;
    place(backbone, motion.backbone_m[k]);
    motion.tendons_m[k].forEach((points, j) => {
      place(tendons[j], points);
    });
    state.tip_m = motion.backbone_m[k][motion.backbone_m[k].length - 1];
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== w || canvas.height !== h) {
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
    renderer.render(scene, camera);
    info.textContent = `${motion.robot}: t = ${motion.t_s[k].toFixed(3)} s`;
    state.ready = true;
    requestAnimationFrame(draw);
  }
  draw();
}

main().catch((e) => { state.error = String(e); info.textContent = `error: ${e}`; console.error(e); });
