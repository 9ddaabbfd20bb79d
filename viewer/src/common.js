// What the viewer (main.js, `tetcut view`) and the live page (live.js, `tetcut serve`) share: the
// three.js view with its lights and orbit controls, the surface's look, sRGB colours, framing.

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

// Errors are shown on the page, not only in the console; `api.error` keeps the first.
export function errorReporter(api, label) {
  const show = (message) => {
    api.error ??= message;
    const box = document.getElementById('error');
    box.textContent = `${label}: ${api.error}`;
    box.style.display = 'block';
  };
  window.addEventListener('error', (event) => show(event.message));
  return show;
}

// Whether WebGL draws on the CPU (SwiftShader, llvmpipe: no GPU, as on servers and in CI).
export function softwareRenderer() {
  const gl = document.createElement('canvas').getContext('webgl');
  const info = gl?.getExtension('WEBGL_debug_renderer_info');
  const name = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : '';
  gl?.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(String(name));
}

// A renderer in `container`, a scene lit by a sky light and a headlight, a camera with orbit
// controls. `draw()` renders once.
export function createView(container, up = new THREE.Vector3(0, 0, 1), { antialias = true } = {}) {
  // preserveDrawingBuffer: screenshots (and the tests) read what is on screen.
  const renderer = new THREE.WebGLRenderer({ antialias, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(container.clientWidth, container.clientHeight);
  renderer.setClearColor(0xf2f2f2);
  container.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x606070, 1.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  scene.add(sun);

  const camera = new THREE.PerspectiveCamera(35, container.clientWidth / container.clientHeight, 1e-3, 1e3);
  camera.up.copy(up);
  const controls = new OrbitControls(camera, renderer.domElement);

  const view = {
    renderer, scene, camera, controls,
    draw() {
      sun.position.copy(camera.position);  // a headlight: every face the camera sees is lit
      renderer.render(scene, camera);
    },
  };
  window.addEventListener('resize', () => {
    camera.aspect = container.clientWidth / container.clientHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(container.clientWidth, container.clientHeight);
    view.draw();
  });
  return view;
}

// The material surface's look: flat-shaded, both sides, pushed back a little so lines stay in front.
export function surfaceMaterial() {
  return new THREE.MeshStandardMaterial({
    vertexColors: true, flatShading: true, side: THREE.DoubleSide, roughness: 0.8, metalness: 0,
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
  });
}

// sRGB bytes (as in tetcut's PNGs) to the linear values three.js lights with.
export const linearOf = Float32Array.from({ length: 256 }, (_, i) => {
  const c = i / 255;
  return c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4;
});

// Places the camera to see all of `box`, from `azimuth` and `elevation` (degrees) about the
// camera's up direction, and aims the controls at its centre.
export function frameBox(view, box, azimuth = 35, elevation = 25) {
  const { camera, controls } = view;
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.1;
  const up = camera.up.clone().normalize();
  // Two directions across `up`: the view turns about it.
  const side = Math.abs(up.z) < 0.9 ? new THREE.Vector3(0, 0, 1) : new THREE.Vector3(1, 0, 0);
  const across = side.sub(up.clone().multiplyScalar(side.dot(up))).normalize();
  const other = new THREE.Vector3().crossVectors(up, across);
  const a = THREE.MathUtils.degToRad(azimuth), e = THREE.MathUtils.degToRad(elevation);
  const direction = across.multiplyScalar(Math.cos(e) * Math.cos(a))
    .add(other.multiplyScalar(Math.cos(e) * Math.sin(a)))
    .add(up.multiplyScalar(Math.sin(e)));
  camera.position.copy(centre).addScaledVector(direction, distance);
  camera.near = distance / 100;
  camera.far = distance * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
  return { centre, radius };
}
