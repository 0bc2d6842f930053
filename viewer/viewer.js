// vismask's viewer: loads a solved mesh (binary glTF from `vismask render
// --export`: POSITION and COLOR_0, linear display radiance) and shows it as
// vismask's image.png shows the solution: radiance interpolated linearly
// across each triangle, times the exposure, clamped to [0, 1] and
// sRGB-encoded per pixel (src/output/image_io.cpp ToneMap), back faces black,
// background black. The first view is run.json's camera, framed as vismask
// frames its image (vertical field of view; a window narrower than the image
// widens it so the image's whole width stays in view).
//
// URL parameters: glb=PATH (the mesh, required), run=PATH (run.json: camera,
// exposure, image size; optional), panel=0 (no control panel, for
// screenshots), aa=0 (no multisampling: one sample at each pixel's centre,
// as vismask's --aa off). When it has drawn its first frame, window.vismaskViewer.ready
// is true; errors go to the page and to console.error.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const params = new URLSearchParams(window.location.search);
const panel = document.getElementById('panel');
const message = document.getElementById('message');
const state = { ready: false, error: null };
window.vismaskViewer = state;

function Fail(text) {
  state.error = text;
  message.textContent = text;
  panel.classList.remove('hidden');
  console.error('vismask viewer: ' + text);
}

// The tone map of src/output/image_io.cpp: v = radiance * exposure; NaN or <= 0 -> 0,
// >= 1 -> 1; the sRGB transfer (IEC 61966-2-1). The framebuffer is 8-bit
// and takes the encoded value as it is (no further conversion: a raw shader
// gets none from three.js).
const kVertexShader = `
precision highp float;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
in vec3 position;
in vec3 color;
out vec3 vRadiance;
void main() {
  vRadiance = color;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
}`;
const kFragmentShader = `
precision highp float;
uniform float exposure;
in vec3 vRadiance;
out vec4 fragColor;
float Encode(float radiance) {
  float v = radiance * exposure;
  v = v > 0.0 ? min(v, 1.0) : 0.0;
  return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
void main() {
  if (!gl_FrontFacing) {  // vismask draws the back of a one-sided polygon black
    fragColor = vec4(0.0, 0.0, 0.0, 1.0);
    return;
  }
  fragColor = vec4(Encode(vRadiance.r), Encode(vRadiance.g), Encode(vRadiance.b), 1.0);
}`;

const material = new THREE.RawShaderMaterial({
  glslVersion: THREE.GLSL3,
  vertexShader: kVertexShader,
  fragmentShader: kFragmentShader,
  uniforms: { exposure: { value: 1.0 } },  // run.json's exposure x 2^stops x the file's radianceScale
  side: THREE.DoubleSide,
});

const renderer = new THREE.WebGLRenderer({ antialias: params.get('aa') !== '0' });
renderer.toneMapping = THREE.NoToneMapping;
renderer.setClearColor(0x000000, 1);
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
document.body.insertBefore(renderer.domElement, panel);
renderer.domElement.tabIndex = 0;

const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(39.3, window.innerWidth / window.innerHeight, 0.1, 1000);
let controls = null;
let needsRender = true;

// What a view starts from (run.json's camera, or the front of the bounds).
const home = {
  eye: new THREE.Vector3(), target: new THREE.Vector3(), up: new THREE.Vector3(0, 1, 0),
  fovy: 39.3, aspect: 1, exposure: 1, size: 1, radianceScale: 1,
};

function Fit() {
  // Vertical fov as vismask; widen it when the window is narrower than the
  // image, so the image's horizontal extent stays inside the window.
  const aspect = window.innerWidth / window.innerHeight;
  const t = Math.tan(THREE.MathUtils.degToRad(home.fovy) / 2);
  const fovy = aspect >= home.aspect ? home.fovy
                                      : THREE.MathUtils.radToDeg(2 * Math.atan(t * home.aspect / aspect));
  camera.fov = fovy;
  camera.aspect = aspect;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  needsRender = true;
}

function ResetView() {
  camera.position.copy(home.eye);
  camera.up.copy(home.up);
  camera.lookAt(home.target);
  if (controls) {
    controls.target.copy(home.target);
    controls.update();
  }
  needsRender = true;
}

// Exposure: a slider in stops around run.json's exposure.
const slider = document.getElementById('exposure');
const exposureValue = document.getElementById('exposure-value');
function SetStops(stops) {
  slider.value = String(stops);
  const e = home.exposure * Math.pow(2, Number(slider.value));
  material.uniforms.exposure.value = e * home.radianceScale;
  const s = Number(slider.value);
  exposureValue.textContent = e.toPrecision(4) + (s === 0 ? '' : ' (' + (s > 0 ? '+' : '') + s.toFixed(2) + ' stops)');
  needsRender = true;
}
slider.addEventListener('input', () => SetStops(Number(slider.value)));

// Fly: drag to look, W/A/S/D or arrows to move, E/Q up and down (along the
// run's up), Shift faster. Orbit: three.js OrbitControls about the target.
const fly = { on: false, keys: new Set(), dragging: false, lastX: 0, lastY: 0, distance: 1 };
const flyBox = document.getElementById('fly');
const keysText = document.getElementById('keys');
function SetFly(on) {
  const wasFlying = fly.on;
  fly.on = on;
  flyBox.checked = on;
  if (on) {
    fly.distance = Math.max(camera.position.distanceTo(controls.target), 1e-6 * home.size);
    controls.enabled = false;
    keysText.textContent = 'drag: look; W A S D / arrows: move; E Q: up, down; Shift: faster';
  } else {
    // Back from flying: orbit about the point the camera looks at, as far
    // away as the orbit's target was when the flight began.
    if (wasFlying) {
      const forward = new THREE.Vector3();
      camera.getWorldDirection(forward);
      controls.target.copy(camera.position).addScaledVector(forward, fly.distance);
    }
    controls.enabled = true;
    controls.update();
    keysText.textContent = 'drag: orbit; right drag: pan; wheel: zoom';
  }
  needsRender = true;
}
flyBox.addEventListener('change', () => SetFly(flyBox.checked));
document.getElementById('reset').addEventListener('click', () => ResetView());

window.addEventListener('keydown', (e) => {
  if (e.target instanceof HTMLInputElement && e.target.type === 'range') return;
  if (e.code === 'KeyF') SetFly(!fly.on);
  else if (e.code === 'Home') ResetView();
  else if (e.key === '+' || e.key === '=') SetStops(Number(slider.value) + 0.25);
  else if (e.key === '-') SetStops(Number(slider.value) - 0.25);
  else fly.keys.add(e.code);
});
window.addEventListener('keyup', (e) => fly.keys.delete(e.code));
window.addEventListener('blur', () => fly.keys.clear());

const canvas = renderer.domElement;
canvas.addEventListener('pointerdown', (e) => {
  if (!fly.on) return;
  fly.dragging = true;
  fly.lastX = e.clientX;
  fly.lastY = e.clientY;
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener('pointerup', () => { fly.dragging = false; });
canvas.addEventListener('pointermove', (e) => {
  if (!fly.on || !fly.dragging) return;
  const perPixel = THREE.MathUtils.degToRad(camera.fov) / window.innerHeight;
  const dx = (e.clientX - fly.lastX) * perPixel, dy = (e.clientY - fly.lastY) * perPixel;
  fly.lastX = e.clientX;
  fly.lastY = e.clientY;
  // Yaw about the run's up; pitch about the camera's right, short of the pole.
  const up = home.up;
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  forward.applyAxisAngle(up, -dx);
  const right = new THREE.Vector3().crossVectors(forward, up).normalize();
  const pitched = forward.clone().applyAxisAngle(right, -dy);
  if (Math.abs(pitched.dot(up)) < 0.995) forward.copy(pitched);
  camera.up.copy(up);
  camera.lookAt(camera.position.clone().add(forward));
  needsRender = true;
});

function StepFly(seconds) {
  const k = fly.keys;
  const move = new THREE.Vector3();
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  const right = new THREE.Vector3().crossVectors(forward, home.up).normalize();
  if (k.has('KeyW') || k.has('ArrowUp')) move.add(forward);
  if (k.has('KeyS') || k.has('ArrowDown')) move.sub(forward);
  if (k.has('KeyD') || k.has('ArrowRight')) move.add(right);
  if (k.has('KeyA') || k.has('ArrowLeft')) move.sub(right);
  if (k.has('KeyE')) move.add(home.up);
  if (k.has('KeyQ')) move.sub(home.up);
  if (move.lengthSq() === 0) return;
  const fast = k.has('ShiftLeft') || k.has('ShiftRight') ? 4 : 1;
  camera.position.addScaledVector(move.normalize(), 0.25 * home.size * fast * seconds);
  needsRender = true;
}

let last = performance.now();
function Frame(now) {
  const seconds = Math.min((now - last) / 1000, 0.1);
  last = now;
  if (fly.on) StepFly(seconds);
  if (needsRender) {
    needsRender = false;
    renderer.render(scene, camera);
    if (!state.ready && !state.error) {
      // Ready once the first frame has been presented.
      requestAnimationFrame(() => requestAnimationFrame(() => { state.ready = true; }));
    }
  }
  requestAnimationFrame(Frame);
}

async function FetchJson(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(url + ': HTTP ' + response.status);
  return response.json();
}

// run.json's options: camera [eye, target, up, fovy], width, height, exposure.
function FromRun(run) {
  const o = run && run.options;
  const c = o && o.camera;
  if (!Array.isArray(c) || c.length !== 10 || !c.every(Number.isFinite))
    throw new Error('run.json: options.camera is not [ex, ey, ez, tx, ty, tz, ux, uy, uz, fovy]');
  if (!(o.width > 0 && o.height > 0)) throw new Error('run.json: options.width and height are not positive');
  if (!(o.exposure > 0)) throw new Error('run.json: options.exposure is not positive');
  home.eye.set(c[0], c[1], c[2]);
  home.target.set(c[3], c[4], c[5]);
  home.up.set(c[6], c[7], c[8]);
  home.fovy = c[9];
  home.aspect = o.width / o.height;
  home.exposure = o.exposure;
}

// Without run.json: vismask's front camera (from -z looking +z, up +y, the
// box's larger extent filling 39.3 degrees with a 4% margin; SideCamera in
// src/display/camera.cpp) and an exposure mapping the log-average vertex luminance
// to middle grey (vismask takes it over pixels, so it may differ a little).
function FromBounds(box, colors) {
  const centre = box.getCenter(new THREE.Vector3());
  const half = box.getSize(new THREE.Vector3()).multiplyScalar(0.5);
  let reach = Math.max(half.x, half.y);
  if (!(reach > 0)) reach = Math.max(half.z, 1);
  const distance = 1.04 * reach / Math.tan(THREE.MathUtils.degToRad(39.3) / 2);
  home.target.set(centre.x, centre.y, box.min.z);
  home.eye.set(centre.x, centre.y, box.min.z - distance);
  home.up.set(0, 1, 0);
  home.fovy = 39.3;
  home.aspect = window.innerWidth / window.innerHeight;
  let sumLog = 0;
  for (let i = 0; i < colors.count; ++i)
    sumLog += Math.log(1e-12 + 0.2126 * colors.getX(i) + 0.7152 * colors.getY(i) + 0.0722 * colors.getZ(i));
  const logAverage = Math.exp(sumLog / Math.max(colors.count, 1));
  home.exposure = logAverage > 1e-11 ? 0.18 / logAverage : 1;
}

// The agreed format: one mesh, triangles, POSITION and COLOR_0 (3 floats).
function TakeMesh(gltf) {
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
  if (meshes.length === 0) throw new Error('the file holds no triangle mesh');
  for (const mesh of meshes) {
    const g = mesh.geometry;
    if (!g.attributes.position) throw new Error('a primitive has no POSITION');
    if (!g.attributes.color || g.attributes.color.itemSize !== 3)
      throw new Error('a primitive has no COLOR_0 of 3 components (the radiance vismask exports)');
    if (mesh.isSkinnedMesh || mesh.isInstancedMesh) throw new Error('not a plain mesh');
    mesh.material = material;
  }
  // COLOR_0 may be stored divided by a power of two, extras.radianceScale
  // (so that it fits in [0, 1]); radiance = COLOR_0 x scale, and a power of
  // two makes COLOR_0 x (scale x exposure) round as radiance x exposure.
  const scales = meshes.map((m) => {
    const s = m.geometry.userData.radianceScale;
    if (s === undefined) return 1;
    if (!(Number.isFinite(s) && s > 0)) throw new Error('extras.radianceScale is not a positive number');
    return s;
  });
  if (scales.some((s) => s !== scales[0])) throw new Error('the primitives differ in extras.radianceScale');
  home.radianceScale = scales[0];
  const used = gltf.parser.json.extensionsUsed || [];
  if (!used.includes('KHR_materials_unlit'))
    console.warn('vismask viewer: KHR_materials_unlit is not in extensionsUsed (the export format has it)');
  return meshes;
}

async function Main() {
  const glb = params.get('glb');
  if (params.get('panel') === '0') panel.classList.add('hidden');
  if (!glb) {
    Fail('no mesh given: open index.html?glb=PATH.glb[&run=PATH/run.json] (vismask view OUT_DIR prints it)');
    return;
  }
  document.getElementById('title').textContent = 'vismask viewer: ' + glb;
  const runUrl = params.get('run');
  // The file's bytes whole (response.arrayBuffer()), then parsed: a
  // streamed read (GLTFLoader.load) sometimes left Chromium reporting the
  // finished request as aborted.
  const [bytes, run] = await Promise.all([
    fetch(glb).then((r) => {
      if (!r.ok) throw new Error(glb + ': HTTP ' + r.status);
      return r.arrayBuffer();
    }),
    runUrl ? FetchJson(runUrl) : Promise.resolve(null),
  ]);
  const gltf = await new GLTFLoader().parseAsync(bytes, '').catch((e) => {
    throw new Error(glb + ': ' + (e.message || e));
  });
  const meshes = TakeMesh(gltf);
  scene.add(gltf.scene);
  gltf.scene.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(gltf.scene);
  if (box.isEmpty()) throw new Error(glb + ': the mesh is empty');
  if (run) FromRun(run);
  else FromBounds(box, meshes[0].geometry.attributes.color);
  home.up.normalize();
  home.size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-12);
  // Clip planes: near as vismask's (1e-3 of the eye's distance to the
  // target), far past everything from wherever the walk goes.
  const eyeDistance = home.eye.distanceTo(home.target);
  camera.near = 1e-3 * eyeDistance;
  camera.far = 4 * (eyeDistance + home.size);
  camera.up.copy(home.up);  // OrbitControls orbits about the up it finds
  controls = new OrbitControls(camera, canvas);
  controls.addEventListener('change', () => { needsRender = true; });
  Fit();
  ResetView();
  SetStops(0);
  SetFly(false);
  window.addEventListener('resize', Fit);
  // For tests: where the camera is and what it orbits about.
  state.view = () => ({ eye: camera.position.toArray(), target: controls.target.toArray() });
  requestAnimationFrame(Frame);
}

Main().catch((e) => Fail(e.message || String(e)));
