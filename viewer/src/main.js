// The tetcut viewer: one self-contained page written by `tetcut view`. The data (frames of a
// material surface, each with its vertices' piece colours and optionally the edges of the mesh it
// is embedded in: tets, or a cloth's triangle copies) sits in the page as JSON with base64 arrays, so the page works offline from file://.
//
// For tests and scripting, window.tetcutViewer exposes the state and the same actions as the
// controls: { ready, frameCount, frame, setFrame(i), setPieces(on), setTets(on), error }.

import * as THREE from 'three';
import { createView, errorReporter, frameBox, linearOf, surfaceMaterial as makeSurfaceMaterial } from './common.js';

const api = { ready: false, frameCount: 0, frame: 0, error: null };
window.tetcutViewer = api;

const showError = errorReporter(api, 'tetcut viewer');
function fail(message) {
  showError(message);
  throw new Error(message);
}

function decode(base64, Type) {
  if (base64 == null) return null;
  const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
  if (bytes.length % Type.BYTES_PER_ELEMENT !== 0) fail(`an array's length is not a whole number of ${Type.name} elements`);
  return new Type(bytes.buffer);
}

function dequantise(p) {
  const q = decode(p.q, Uint16Array), out = new Float32Array(q.length);
  for (let i = 0; i < q.length; ++i) out[i] = p.min[i % 3] + q[i] * p.step[i % 3];
  return out;
}

// Frames share arrays with the frame before them when the topology did not change (null in the
// data): resolve those references up front (which only copies base64 strings), and decode a
// frame's arrays when it is first shown, so a long simulation opens at once.
function readFrames(data) {
  if (!Array.isArray(data.frames) || data.frames.length === 0) fail('the page holds no frames');
  const frames = [];
  let triangles = null, colours = null, edges = null;
  for (const [i, f] of data.frames.entries()) {
    triangles = f.surface.triangles ?? triangles;
    colours = f.surface.colours ?? colours;
    if (!triangles || !colours) fail(`frame ${i} has no triangles`);
    if (f.mesh) edges = f.mesh.edges ?? edges;
    frames.push({ time: f.time, pieces: f.surface.pieces, source: { f, triangles, colours, edges }, decoded: null });
  }
  return frames;
}

// Typed arrays of a frame, decoded once; frames that share connectivity share its arrays.
const decodedArrays = new Map();
function shared(base64, Type) {
  if (!decodedArrays.has(base64)) decodedArrays.set(base64, decode(base64, Type));
  return decodedArrays.get(base64);
}
function decoded(frame) {
  if (!frame.decoded) {
    const { f, triangles, colours, edges } = frame.source;
    frame.decoded = {
      positions: dequantise(f.surface.positions),
      triangles: shared(triangles, Uint32Array),
      colours: shared(colours, Uint8Array),
      mesh: f.mesh ? { positions: dequantise(f.mesh.positions), edges: shared(edges, Uint32Array) } : null,
    };
  }
  return frame.decoded;
}

const data = JSON.parse(document.getElementById('tetcut-data').textContent);
const frames = readFrames(data);
api.frameCount = frames.length;
document.getElementById('title').textContent = data.title ?? 'tetcut';
// What the mesh edges are: an embedding tet mesh's, or a cloth's triangle copies.
const meshName = data.mesh_kind === 'triangles' ? { control: 'triangle copies', stats: 'triangle' }
                                                : { control: 'embedding tets', stats: 'tet' };
document.getElementById('tets-label').textContent = meshName.control;

// --- scene -----------------------------------------------------------------------------------
const container = document.getElementById('view');
const view = createView(container);  // tetcut's pictures and scenes are z-up
const { scene, camera, controls } = view;
const draw = () => view.draw();
controls.addEventListener('change', draw);

const surfaceMaterial = makeSurfaceMaterial();
const plainColour = new THREE.Color(0xc8c8cd);  // (THREE.Color converts hex from sRGB)
const edgeMaterial = new THREE.LineBasicMaterial({ color: 0x303040, transparent: true, opacity: 0.45 });
const surfaceMesh = new THREE.Mesh(new THREE.BufferGeometry(), surfaceMaterial);
const tetLines = new THREE.LineSegments(new THREE.BufferGeometry(), edgeMaterial);
scene.add(surfaceMesh, tetLines);

// Frame the bounds of every frame (each frame's quantisation box, known without decoding it), so
// the camera holds still while stepping and nothing moves out of view.
{
  const box = new THREE.Box3();
  for (const frame of frames) {
    for (const { min, step } of [frame.source.f.surface.positions, frame.source.f.mesh?.positions].filter(Boolean)) {
      box.expandByPoint(new THREE.Vector3(...min));
      box.expandByPoint(new THREE.Vector3(min[0] + 65535 * step[0], min[1] + 65535 * step[1], min[2] + 65535 * step[2]));
    }
  }
  frameBox(view, box);
}

// --- state -----------------------------------------------------------------------------------
const state = { frame: -1, pieces: true, tets: false, playing: false };
const ui = {
  slider: document.getElementById('slider'),
  label: document.getElementById('frame-label'),
  stats: document.getElementById('stats'),
  pieces: document.getElementById('pieces'),
  tets: document.getElementById('tets'),
  play: document.getElementById('play'),
};
ui.slider.max = String(frames.length - 1);
ui.tets.disabled = !frames.some((f) => f.source.f.mesh);

function surfaceColours(frame) {
  if (state.pieces) return new THREE.Float32BufferAttribute(Float32Array.from(frame.colours, (c) => linearOf[c]), 3);
  const n = frame.positions.length / 3, plain = new Float32Array(3 * n);
  for (let i = 0; i < n; ++i) plain.set([plainColour.r, plainColour.g, plainColour.b], 3 * i);
  return new THREE.Float32BufferAttribute(plain, 3);
}

function show() {
  const frame = decoded(frames[state.frame]);
  const pieces = frames[state.frame].pieces, time = frames[state.frame].time;
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(frame.positions, 3));
  geometry.setAttribute('color', surfaceColours(frame));
  geometry.setIndex(new THREE.BufferAttribute(frame.triangles, 1));
  surfaceMesh.geometry.dispose();
  surfaceMesh.geometry = geometry;

  const lines = new THREE.BufferGeometry();
  if (frame.mesh && state.tets) {
    lines.setAttribute('position', new THREE.BufferAttribute(frame.mesh.positions, 3));
    lines.setIndex(new THREE.BufferAttribute(frame.mesh.edges, 1));
  }
  tetLines.geometry.dispose();
  tetLines.geometry = lines;
  tetLines.visible = Boolean(frame.mesh && state.tets);

  ui.slider.value = String(state.frame);
  ui.label.textContent = `frame ${state.frame + 1} / ${frames.length}` +
    (time != null ? `  \u00b7  t = ${time.toFixed(3)} s` : '');
  ui.stats.textContent = `${frame.triangles.length / 3} triangles, ${pieces} piece${pieces === 1 ? '' : 's'}` +
    (frame.mesh ? `, ${frame.mesh.edges.length / 2} ${meshName.stats} edges` : '');
  api.frame = state.frame;
  draw();
}

api.setFrame = (i) => {
  state.frame = Math.min(Math.max(0, Math.trunc(i)), frames.length - 1);
  show();
};
api.setPieces = (on) => { state.pieces = Boolean(on); ui.pieces.checked = state.pieces; show(); };
api.setTets = (on) => { state.tets = Boolean(on) && !ui.tets.disabled; ui.tets.checked = state.tets; show(); };

let timer = null;
function setPlaying(on) {
  state.playing = on && frames.length > 1;
  ui.play.innerHTML = state.playing ? '&#10074;&#10074;' : '&#9654;';
  clearInterval(timer);
  if (state.playing) timer = setInterval(() => api.setFrame((state.frame + 1) % frames.length), 1000 / 24);
}

document.getElementById('prev').addEventListener('click', () => api.setFrame(state.frame - 1));
document.getElementById('next').addEventListener('click', () => api.setFrame(state.frame + 1));
ui.play.addEventListener('click', () => setPlaying(!state.playing));
ui.slider.addEventListener('input', () => api.setFrame(Number(ui.slider.value)));
ui.pieces.addEventListener('change', () => api.setPieces(ui.pieces.checked));
ui.tets.addEventListener('change', () => api.setTets(ui.tets.checked));
window.addEventListener('keydown', (event) => {
  if (event.key === 'ArrowRight') api.setFrame(state.frame + 1);
  else if (event.key === 'ArrowLeft') api.setFrame(state.frame - 1);
  else if (event.key === ' ') { setPlaying(!state.playing); event.preventDefault(); }
});

api.setFrame(0);
api.ready = true;
