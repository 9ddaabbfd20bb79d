// The live page of `tetcut serve`: a simulated object streamed over a WebSocket, cut with a
// scalpel, pulled with a hook and pinned with the mouse. The server sends the cut mesh's topology
// (tet copies, the material surface embedded in them, piece colours) when a cut changes it and
// the nodes' positions every step; the page places the surface's vertices from the nodes (see
// src/server/live_protocol.hpp for the messages).
//
// For tests and scripting, window.tetcutLive exposes the state and the tools:
// { ready, connected, framesReceived, topologies, pieces, stats, errors, fps, cutLatencies, tool,
//   setTool(name), screenOf([x, y, z]), hitAt(x, y), surfaceBox(), recording(), error }.

import * as THREE from 'three';
import { createView, errorReporter, frameBox, linearOf, softwareRenderer, surfaceMaterial } from './common.js';

const api = {
  ready: false, connected: false, framesReceived: 0, topologies: 0, version: 0, pieces: 0,
  stats: null, errors: [], fps: 0, tool: 'scalpel', error: null,
  // Milliseconds from a blade pose that cut the material leaving the page to the first frame
  // that shows the cut (the server's "cut" reply names the topology that holds it): how soon a
  // cut is seen.
  cutLatencies: [],
  // Where that time went, a row per cut seen: milliseconds from the pose leaving to the server's
  // "cut" reply arriving, to its topology arriving, to that topology read, to its first frame.
  cutPhases: [],
  // Milliseconds the page spent reading each topology message, and drawing each frame.
  topologyMs: [], drawMs: [],
  // The size of each topology message (bytes): whole when the page joins, the patches a cut
  // changed after that.
  topologyBytes: [],
};
const bladeSentAt = new Map();  // blade poses' seq -> when they left, until answered or stale
const cutSentAt = new Map();    // topology version -> when the first pose it shows left
const cutReplyAt = new Map();   // topology version -> when the "cut" reply naming it arrived
let topologyArrivedAt = 0, topologyReadAt = 0;  // when the last topology message arrived, and when it was read (a cut's phases, below)
window.tetcutLive = api;
const showError = errorReporter(api, 'tetcut live');

const config = JSON.parse(document.getElementById('tetcut-config').textContent);
const token = new URLSearchParams(window.location.search).get('token') ?? '';

// --- view ------------------------------------------------------------------------------------
const container = document.getElementById('view');
const gravity = new THREE.Vector3(...(config.gravity ?? [0, 0, -9.81]));
// Up is against gravity, so the object stands as it hangs or rests.
const up = gravity.lengthSq() > 0 ? gravity.clone().negate().normalize() : new THREE.Vector3(0, 0, 1);
// Multisampling on a GPU; not where the CPU draws (4 times the fragments, 30 times a second, on
// the cores the simulation needs when it is served from the same machine).
const view = createView(container, up, { antialias: !softwareRenderer() });
const { scene, camera, controls } = view;
let dirty = true;
controls.addEventListener('change', () => { dirty = true; });

const surface = new THREE.Mesh(new THREE.BufferGeometry(), surfaceMaterial());
surface.visible = false;
scene.add(surface);
const markers = new THREE.Group();
scene.add(markers);
const markerGeometry = new THREE.SphereGeometry(1, 16, 12);
const hookMaterial = new THREE.MeshBasicMaterial({ color: 0xd04020 });
const pinMaterial = new THREE.MeshBasicMaterial({ color: 0x2050c0 });
const bladeMaterial = new THREE.LineBasicMaterial({ color: 0x202020 });
const blade = new THREE.Line(new THREE.BufferGeometry(), bladeMaterial);
blade.visible = false;
scene.add(blade);

let topology = null;  // the latest topology: { version, nodeCount, nodePiece, pieces }
let awaitingFrame = false;  // a topology changed the arrays and no frame of it has come yet
let nodes = null;     // node positions of the latest frame (Float32Array, 3 per node)
let framed = false;   // the camera has been aimed at the object
let size = 1;         // the object's radius when first framed: the tools' scale

function fail(message) {
  showError(message);
  throw new Error(message);
}

// --- messages --------------------------------------------------------------------------------
// The material surface in patches, one per input tet, kept in ranges of shared arrays so that a
// topology change rewrites only the patches it carries: O(changed patches) a cut, not O(surface).
// A patch replaced by a larger one moves to the end; the ranges it leaves are dead (their
// triangles degenerate, never drawn) until dead outweighs live, and then the arrays are packed.
const patches = new Map();  // input tet -> { corners, weights, triangles (local), vertexAt, vertexRoom, triangleAt, triangleRoom }
const arrays = { vertexRoom: 0, triangleRoom: 0, vertexEnd: 0, triangleEnd: 0, liveVertices: 0, liveTriangles: 0 };

// New arrays of room for `vertexRoom` vertices and `triangleRoom` triangles, the live patches
// packed at their start.
function allocate(vertexRoom, triangleRoom) {
  arrays.vertexRoom = vertexRoom;
  arrays.triangleRoom = triangleRoom;
  arrays.corners = new Uint32Array(4 * vertexRoom);
  arrays.weights = new Float32Array(4 * vertexRoom);
  arrays.colours = new Float32Array(3 * vertexRoom);
  arrays.index = new Uint32Array(3 * triangleRoom);
  arrays.vertexEnd = 0;
  arrays.triangleEnd = 0;
  for (const p of patches.values()) place(p, true);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * vertexRoom), 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(arrays.colours, 3));
  geometry.setIndex(new THREE.BufferAttribute(arrays.index, 1));
  surface.geometry.dispose();
  surface.geometry = geometry;
}

// Writes a patch into its ranges, or (`fresh`, or it does not fit) into new ones at the end.
function place(p, fresh) {
  const n = p.weights.length / 4, m = p.triangles.length / 3;
  if (fresh || n > p.vertexRoom || m > p.triangleRoom) {
    p.vertexAt = arrays.vertexEnd;
    p.triangleAt = arrays.triangleEnd;
    p.vertexRoom = n;
    p.triangleRoom = m;
    arrays.vertexEnd += n;
    arrays.triangleEnd += m;
  }
  arrays.corners.set(p.corners, 4 * p.vertexAt);
  arrays.weights.set(p.weights, 4 * p.vertexAt);
  const index = arrays.index, local = p.triangles, at = 3 * p.triangleAt;
  for (let k = 0; k < local.length; ++k) index[at + k] = local[k] + p.vertexAt;
  clear(p, n, m);
}

// Makes a patch's ranges from vertex `n` and triangle `m` on dead: degenerate triangles, and
// vertices on node 0 with no weight.
function clear(p, n, m) {
  arrays.index.fill(0, 3 * (p.triangleAt + m), 3 * (p.triangleAt + p.triangleRoom));
  arrays.corners.fill(0, 4 * (p.vertexAt + n), 4 * (p.vertexAt + p.vertexRoom));
  arrays.weights.fill(0, 4 * (p.vertexAt + n), 4 * (p.vertexAt + p.vertexRoom));
}

function readTopology(buffer) {
  if (buffer.byteLength < 40) fail('a topology message is shorter than its header');
  const [, version, base, nodeCount, pieces, patchCount, vertices, triangles, flags] = new Uint32Array(buffer, 0, 10);
  if (base !== 0 && base !== topology?.version) fail(`a topology change from version ${base}, but the page has ${topology?.version}`);
  let offset = 40;
  const take = (Type, count) => {
    if (offset + count * Type.BYTES_PER_ELEMENT > buffer.byteLength) fail('a topology message is shorter than its counts');
    const array = new Type(buffer, offset, count);
    offset += Math.ceil((count * Type.BYTES_PER_ELEMENT) / 4) * 4;  // sections are 4-byte aligned
    return array;
  };
  // 16-bit indices where the flags say so (see live_protocol.hpp).
  const nodeIndex = flags & 1 ? Uint16Array : Uint32Array;
  const nodePiece = take(nodeIndex, nodeCount).slice();
  const pieceColours = take(Uint8Array, 4 * pieces).slice();
  // The patches the message carries, read and checked before anything changes.
  const carried = [];
  for (let i = 0; i < patchCount; ++i) {
    const [tet, n, m] = take(Uint32Array, 3);
    if (m === 0) {
      if (n !== 0) fail(`a patch of ${n} vertices and no triangles`);
      carried.push([tet, null]);
      continue;
    }
    // Each vertex's four nodes and weights, once, so that a frame costs 12 multiply-adds a vertex.
    const corners = Uint32Array.from(take(nodeIndex, 4 * n));
    for (let k = 0; k < corners.length; ++k) if (corners[k] >= nodeCount) fail(`tet ${tet}'s patch names node ${corners[k]} of ${nodeCount}`);
    const quantised = take(Uint16Array, 3 * n);
    const weights = new Float32Array(4 * n);
    for (let v = 0; v < n; ++v) {
      let rest = 1;
      for (let k = 0; k < 3; ++k) {
        const w = quantised[3 * v + k] / 65535;
        weights[4 * v + k] = w;
        rest -= w;
      }
      weights[4 * v + 3] = rest;
    }
    const local = take(flags & 2 && n <= 65536 ? Uint16Array : Uint32Array, 3 * m).slice();
    for (let k = 0; k < local.length; ++k) if (local[k] >= n) fail(`a triangle of tet ${tet}'s patch names vertex ${local[k]} of ${n}`);
    carried.push([tet, { corners, weights, triangles: local }]);
  }
  if (offset !== buffer.byteLength) fail('a topology message is longer than its counts');
  for (const [tet, p] of carried) if (!p && !(base !== 0 && patches.has(tet))) fail(`a topology removes tet ${tet}'s patch, which the page does not have`);

  // Apply: the patches that fit their ranges in place, the others at the end (packing first when
  // the dead ranges would outweigh the live ones, or the room runs out).
  if (base === 0) {
    patches.clear();
    arrays.liveVertices = 0;
    arrays.liveTriangles = 0;
  }
  let growVertices = 0, growTriangles = 0;
  for (const [tet, p] of carried) {
    const old = patches.get(tet);
    if (old) {
      arrays.liveVertices -= old.weights.length / 4;
      arrays.liveTriangles -= old.triangles.length / 3;
    }
    if (!p) {
      if (old) clear(old, 0, 0);
      patches.delete(tet);
      continue;
    }
    arrays.liveVertices += p.weights.length / 4;
    arrays.liveTriangles += p.triangles.length / 3;
    if (old) Object.assign(p, { vertexAt: old.vertexAt, vertexRoom: old.vertexRoom, triangleAt: old.triangleAt, triangleRoom: old.triangleRoom });
    else Object.assign(p, { vertexAt: 0, vertexRoom: 0, triangleAt: 0, triangleRoom: 0 });
    if (p.weights.length / 4 > p.vertexRoom || p.triangles.length / 3 > p.triangleRoom) {
      if (old) clear(old, 0, 0);
      growVertices += p.weights.length / 4;
      growTriangles += p.triangles.length / 3;
      p.moves = true;
    }
    patches.set(tet, p);
  }
  if (arrays.liveVertices !== vertices || arrays.liveTriangles !== triangles) {
    fail(`the patches hold ${arrays.liveVertices} vertices and ${arrays.liveTriangles} triangles, the message says ${vertices} and ${triangles}`);
  }
  const ends = [arrays.vertexEnd + growVertices, arrays.triangleEnd + growTriangles];
  if (base === 0 || ends[0] > arrays.vertexRoom || ends[1] > arrays.triangleRoom || ends[0] > 2 * vertices + 1024 || ends[1] > 2 * triangles + 1024) {
    for (const p of patches.values()) delete p.moves;
    allocate(Math.ceil(1.25 * vertices) + 1024, Math.ceil(1.25 * triangles) + 1024);  // every patch placed afresh
  } else {
    for (const [, p] of carried) {
      if (!p) continue;
      place(p, p.moves === true);
      delete p.moves;
    }
  }

  // Colours by piece (a cut renumbers the pieces), and the ranges to draw.
  const colours = arrays.colours, corners = arrays.corners;
  for (let v = 0; v < arrays.vertexEnd; ++v) {
    const piece = nodePiece[corners[4 * v]];
    if (piece >= pieces) fail(`a node is in piece ${piece} of ${pieces}`);
    for (let c = 0; c < 3; ++c) colours[3 * v + c] = linearOf[pieceColours[4 * piece + c]];
  }
  const geometry = surface.geometry;
  geometry.getAttribute('color').needsUpdate = true;
  geometry.index.needsUpdate = true;
  geometry.setDrawRange(0, 3 * arrays.triangleEnd);
  topology = { version, pieces, nodeCount, nodePiece };
  // Not drawn until a frame of it places the new vertices (until then the old picture stays).
  awaitingFrame = true;
  api.topologies += 1;
  api.version = version;
  api.pieces = pieces;
}

function readFrame(buffer) {
  const [, version, , nodeCount, pieces] = new Uint32Array(buffer, 0, 6);
  if (!topology || version !== topology.version) return;  // a frame of a topology not seen yet
  if (nodeCount !== topology.nodeCount) fail('a frame has a different number of nodes than its topology');
  const boxes = new Float32Array(buffer, 32, 6 * pieces);
  const q = new Uint16Array(buffer, 32 + 24 * pieces, 3 * nodeCount);
  if (!nodes || nodes.length !== 3 * nodeCount) nodes = new Float32Array(3 * nodeCount);
  const piece = topology.nodePiece;
  for (let n = 0; n < nodeCount; ++n) {
    const b = 6 * piece[n];
    for (let c = 0; c < 3; ++c) nodes[3 * n + c] = boxes[b + c] + q[3 * n + c] * boxes[b + 3 + c];
  }
  const position = surface.geometry.getAttribute('position');
  const out = position.array, w = arrays.weights, corner = arrays.corners;
  for (let v = 0; v < arrays.vertexEnd; ++v) {
    let x = 0, y = 0, z = 0;
    for (let k = 0; k < 4; ++k) {
      const weight = w[4 * v + k], node = 3 * corner[4 * v + k];
      x += weight * nodes[node];
      y += weight * nodes[node + 1];
      z += weight * nodes[node + 2];
    }
    out[3 * v] = x;
    out[3 * v + 1] = y;
    out[3 * v + 2] = z;
  }
  position.needsUpdate = true;
  surface.geometry.boundingSphere = null;  // recomputed when picking
  surface.geometry.boundingBox = null;
  surface.visible = true;
  api.framesReceived += 1;
  if (awaitingFrame) {
    awaitingFrame = false;
    // Seen: the cuts this topology shows (and any an older one showed, dropped unseen).
    for (const [v, sentAt] of cutSentAt) {
      if (v > topology.version) continue;
      const now = performance.now();
      api.cutLatencies.push(now - sentAt);
      const reply = cutReplyAt.get(v) ?? topologyArrivedAt;
      api.cutPhases.push([reply - sentAt, topologyArrivedAt - reply, topologyReadAt - topologyArrivedAt, now - topologyReadAt]);
      cutSentAt.delete(v);
      cutReplyAt.delete(v);
    }
  }
  if (!framed) {
    size = frameBox(view, liveBox(), 35, 10).radius;
    framed = true;
  }
  dirty = true;
}

// The bounds of the drawn triangles' corners (dead vertices, at the origin, left out). O(F).
function liveBox() {
  const box = new THREE.Box3(), p = new THREE.Vector3();
  const index = arrays.index, position = surface.geometry.getAttribute('position').array;
  for (let i = 0; i < 3 * arrays.triangleEnd; i += 3) {
    if (index[i] === index[i + 1] && index[i] === index[i + 2]) continue;  // dead
    for (let k = 0; k < 3; ++k) box.expandByPoint(p.fromArray(position, 3 * index[i + k]));
  }
  return box;
}

const ui = {
  stats: document.getElementById('stats'),
  message: document.getElementById('message'),
  pause: document.getElementById('pause'),
  depth: document.getElementById('depth'),
};

function readText(text) {
  const message = JSON.parse(text);
  if (message.type === 'stats') {
    api.stats = message;
    ui.pause.textContent = message.paused ? 'go on' : 'pause';
  } else if (message.type === 'error') {
    api.errors.push(message.message);
    ui.message.textContent = message.message;
  } else if (message.type === 'cut') {
    // Which topology shows the cut of a blade pose (it comes before that topology).
    const sentAt = bladeSentAt.get(message.seq);
    if (sentAt !== undefined) cutSentAt.set(message.version, Math.min(sentAt, cutSentAt.get(message.version) ?? Infinity));
    if (!cutReplyAt.has(message.version)) cutReplyAt.set(message.version, performance.now());
    for (const s of bladeSentAt.keys()) if (s <= message.seq) bladeSentAt.delete(s);
  } else if (message.type === 'grabbed') {
    hookGrabbed(message);
  } else if (message.type === 'reset') {
    drag = null;
    markers.clear();
    dirty = true;
  }
  showStats();
}

function showStats() {
  const s = api.stats;
  const lines = [`${api.fps.toFixed(0)} frames/s received`];
  if (s) {
    lines.push(`${s.steps_per_second.toFixed(0)} steps/s, step ${s.step_ms.toFixed(1)} ms`);
    lines.push(`cut ${s.cut_ms.toFixed(1)} ms + surface ${s.surface_ms.toFixed(1)} ms`);
    lines.push(`${s.pieces} piece${s.pieces === 1 ? '' : 's'}, ${s.tets} tets, ${s.nodes} nodes`);
    lines.push(`${s.surface_triangles} surface triangles`);
    lines.push(`t = ${s.time.toFixed(2)} s${s.paused ? ' (paused)' : ''}`);
  }
  ui.stats.textContent = lines.join('\n');
}

// --- connection ------------------------------------------------------------------------------
const socket = new WebSocket(`ws://${window.location.host}/live?token=${encodeURIComponent(token)}`);
socket.binaryType = 'arraybuffer';
let seq = 0;
function send(message) {
  if (socket.readyState !== WebSocket.OPEN) return -1;
  message.seq = ++seq;
  socket.send(JSON.stringify(message));
  return seq;
}
socket.addEventListener('open', () => { api.connected = true; });
socket.addEventListener('close', () => {
  api.connected = false;
  ui.message.textContent = 'the server closed the connection';
});
socket.addEventListener('message', (event) => {
  if (typeof event.data === 'string') return readText(event.data);
  const kind = new Uint32Array(event.data, 0, 1)[0];
  if (kind === 1) {
    topologyArrivedAt = performance.now();
    if (api.topologyBytes.length < 10000) api.topologyBytes.push(event.data.byteLength);
    readTopology(event.data);
    topologyReadAt = performance.now();
    api.topologyMs.push(topologyReadAt - topologyArrivedAt);
  }
  else if (kind === 2) readFrame(event.data);
  else fail(`a message of unknown kind ${kind}`);
});

// Frames received per second, over the last second.
let counted = 0, countedAt = performance.now();
setInterval(() => {
  const now = performance.now();
  api.fps = (api.framesReceived - counted) / ((now - countedAt) / 1000);
  counted = api.framesReceived;
  countedAt = now;
  showStats();
}, 1000);

// --- tools -----------------------------------------------------------------------------------
const raycaster = new THREE.Raycaster();
function rayAt(event) {
  const rect = view.renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1, -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
  return raycaster.ray;
}
function pick(event) {
  if (!surface.visible) return null;
  rayAt(event);
  surface.geometry.computeBoundingSphere();
  const hits = raycaster.intersectObject(surface, false);
  return hits.length > 0 ? hits[0].point.clone() : null;
}
// Where the cursor is on the plane through `point` that faces the camera.
function onPlane(event, plane) {
  return rayAt(event).intersectPlane(plane, new THREE.Vector3());
}
const xyz = (v) => [v.x, v.y, v.z];

function marker(point, material, radius) {
  const m = new THREE.Mesh(markerGeometry, material);
  m.position.copy(point);
  m.scale.setScalar(radius);
  markers.add(m);
  dirty = true;
  return m;
}

let drag = null;  // the stroke, hook or pin being made
const pendingHooks = new Map();  // grab's seq -> the drag waiting for its hook number

// The blade's edge for the cursor at `point` on the stroke's plane: for a stroke begun on the
// surface, from a little in front of that depth to `depth` beyond it along the view; for one
// begun beside the model (the plane through its centre), `depth` centred on the plane.
function bladeFrom(point, onSurface = true) {
  const depth = Number(ui.depth.value) * size;
  const a = point.clone().addScaledVector(drag.direction, onSurface ? -0.05 * depth : -0.5 * depth);
  const b = point.clone().addScaledVector(drag.direction, onSurface ? depth : 0.5 * depth);
  blade.geometry.dispose();
  blade.geometry = new THREE.BufferGeometry().setFromPoints([a, b]);
  blade.visible = true;
  dirty = true;
  sendBlade({ type: 'blade', a: xyz(a), b: xyz(b), cuts: drag.poses++ > 0 });
}

// Blade poses go out at most one per kBladeInterval (the server cuts each as it comes, and a
// pointer moves more often than the simulation steps); the latest pose waits for its turn.
const kBladeInterval = 30;
let bladeLastSent = -Infinity, bladeWaiting = null, bladeTimer = null;
function sendBlade(message) {
  bladeWaiting = message;
  const wait = bladeLastSent + kBladeInterval - performance.now();
  if (wait > 0 && message.cuts) {  // a stroke's first pose goes at once: it is where the cut begins
    bladeTimer ??= setTimeout(flushBlade, wait);
    return;
  }
  flushBlade();
}
function flushBlade() {
  clearTimeout(bladeTimer);
  bladeTimer = null;
  if (!bladeWaiting) return;
  delete bladeWaiting.cuts;
  const sent = send(bladeWaiting);
  if (sent > 0) {
    bladeSentAt.set(sent, performance.now());
    // Poses beside the object are never answered: forget the oldest.
    if (bladeSentAt.size > 256) bladeSentAt.delete(bladeSentAt.keys().next().value);
  }
  bladeWaiting = null;
  bladeLastSent = performance.now();
}

function hookGrabbed(message) {
  const waiting = pendingHooks.get(message.seq);
  pendingHooks.delete(message.seq);
  if (!waiting) return;
  waiting.hook = message.hook;
  if (waiting.released) send({ type: 'release', hook: message.hook });
  else if (waiting.target) send({ type: 'move_hook', hook: message.hook, target: xyz(waiting.target) });
}

function onDown(event) {
  if (event.button !== 0 || drag || !surface.visible) return;  // the other buttons orbit and pan
  const hit = pick(event);
  // The scalpel may start off the model (a stroke from outside across it); hook and pin need it.
  if (!hit && api.tool !== 'scalpel') return;
  event.preventDefault();
  container.setPointerCapture(event.pointerId);
  if (api.tool === 'scalpel') {
    const direction = rayAt(event).direction.clone();
    // The stroke keeps the depth where it began: the picked surface point's, or (begun beside
    // the model) the object's centre's.
    const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(direction.clone().negate(), hit ?? controls.target);
    drag = { tool: 'scalpel', direction, plane, onSurface: hit !== null, pointer: event.pointerId, poses: 0 };
    const point = hit ?? onPlane(event, plane);
    if (point) bladeFrom(point, drag.onSurface);
    return;
  }
  const point = hit;
  const direction = point.clone().sub(camera.position).normalize();
  const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(direction.clone().negate(), point);
  if (api.tool === 'hook') {
    drag = { tool: 'hook', plane, pointer: event.pointerId, hook: null, target: null, released: false };
    drag.marker = marker(point, hookMaterial, 0.02 * size);
    pendingHooks.set(send({ type: 'grab', point: xyz(point) }), drag);
  } else {
    const radius = 0.08 * size;
    if (event.shiftKey) {
      send({ type: 'unpin', point: xyz(point), radius });
      for (const m of [...markers.children]) if (m.material === pinMaterial && m.position.distanceTo(point) < radius) markers.remove(m);
      dirty = true;
    } else {
      send({ type: 'pin', point: xyz(point), radius });
      marker(point, pinMaterial, 0.015 * size);
    }
  }
}

function onMove(event) {
  if (!drag || event.pointerId !== drag.pointer) return;
  if (drag.tool === 'scalpel') {
    // Along the surface where the cursor is on it, about the object's centre where it is not.
    // On the plane the stroke began in (no picking as it moves: a ray against the whole
    // surface costs more than a frame on a fine surface).
    const point = onPlane(event, drag.plane);
    if (point) bladeFrom(point, drag.onSurface);
  } else if (drag.tool === 'hook') {
    const target = onPlane(event, drag.plane);
    if (!target) return;
    drag.target = target;
    drag.marker.position.copy(target);
    dirty = true;
    if (drag.hook !== null) send({ type: 'move_hook', hook: drag.hook, target: xyz(target) });
  }
}

function onUp(event) {
  if (!drag || event.pointerId !== drag.pointer) return;
  if (drag.tool === 'scalpel') {
    flushBlade();
    send({ type: 'lift' });
    blade.visible = false;
    dirty = true;
  } else if (drag.tool === 'hook') {
    if (drag.hook !== null) send({ type: 'release', hook: drag.hook });
    else drag.released = true;
    markers.remove(drag.marker);
    dirty = true;
  }
  drag = null;
}

// The left button is the tool's; the orbit controls take the right (orbit) and the middle (pan).
controls.mouseButtons = { LEFT: null, MIDDLE: THREE.MOUSE.PAN, RIGHT: THREE.MOUSE.ROTATE };
container.addEventListener('contextmenu', (event) => event.preventDefault());
container.addEventListener('pointerdown', onDown, { capture: true });
container.addEventListener('pointermove', onMove, { capture: true });
container.addEventListener('pointerup', onUp, { capture: true });
container.addEventListener('pointercancel', onUp, { capture: true });

api.setTool = (name) => {
  if (!['scalpel', 'hook', 'pin'].includes(name)) throw new Error(`no tool '${name}'`);
  api.tool = name;
  document.querySelector(`input[name=tool][value=${name}]`).checked = true;
  container.className = name;
};
for (const input of document.querySelectorAll('input[name=tool]')) {
  input.addEventListener('change', () => api.setTool(input.value));
}
api.setTool('scalpel');

document.getElementById('pause').addEventListener('click', () => send({ type: 'pause', paused: !(api.stats?.paused ?? false) }));
document.getElementById('reset').addEventListener('click', () => send({ type: 'reset' }));
api.recording = async () => {
  const response = await fetch(`/api/recording?token=${encodeURIComponent(token)}`);
  if (!response.ok) throw new Error(`the recording: HTTP ${response.status}`);
  return response.text();
};
document.getElementById('download').addEventListener('click', async () => {
  const text = await api.recording();
  const link = document.createElement('a');
  link.href = URL.createObjectURL(new Blob([text], { type: 'application/json' }));
  link.download = 'tetcut-recording.json';
  link.click();
  setTimeout(() => URL.revokeObjectURL(link.href), 1000);
});
window.addEventListener('keydown', (event) => {
  if (event.key === '1') api.setTool('scalpel');
  else if (event.key === '2') api.setTool('hook');
  else if (event.key === '3') api.setTool('pin');
  else if (event.key === ' ') { document.getElementById('pause').click(); event.preventDefault(); }
});

// For tests: where a world point is on the page, and the surface's current bounds.
api.screenOf = ([x, y, z]) => {
  const p = new THREE.Vector3(x, y, z).project(camera);
  const rect = view.renderer.domElement.getBoundingClientRect();
  return { x: rect.left + (p.x + 1) / 2 * rect.width, y: rect.top + (1 - p.y) / 2 * rect.height };
};
api.hitAt = (x, y) => {
  const point = pick({ clientX: x, clientY: y });
  return point ? xyz(point) : null;
};
api.surfaceBox = () => {
  if (!surface.visible) return null;
  const { min, max } = liveBox();
  return { min: xyz(min), max: xyz(max) };
};

function animate() {
  if (dirty && !awaitingFrame) {
    const start = performance.now();
    view.draw();
    view.renderer.getContext().finish();  // the drawing's own time, not the next frame's
    if (api.drawMs.length < 10000) api.drawMs.push(performance.now() - start);
    dirty = false;
  }
  requestAnimationFrame(animate);
}
requestAnimationFrame(animate);
api.ready = true;
