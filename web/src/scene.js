// What the page draws: a three.js renderer, one camera, the triangles of every chunk in one
// BatchedMesh and the points of each chunk in a THREE.Points, with shading that matches vdiso's
// own renderer (io/render/renderer.h): a headlight at the eye, a little ambient, two-sided.
//
// Why one BatchedMesh. A frame is thousands of chunks (one per brick, a few hundred triangles
// each on a 1024^3 volume). As one THREE.Mesh each, every frame pays a draw call per chunk
// (uniform uploads, state checks, ANGLE's validation) on the page's main thread. A BatchedMesh
// keeps all chunks in one vertex and one index buffer and draws the visible ones with a single
// WEBGL_multi_draw call; each chunk is an instance whose matrix maps the unit cube of its
// normalized u16 positions onto its box, so positions stay 6 bytes on the GPU, and showing or
// hiding a chunk, which frames do all the time, is a flag. Measured in headless chromium 156
// (SwiftShader, 800x800), 4096 chunks of 72 triangles: render() took 4.4 ms of main-thread time
// as one BatchedMesh against 45 ms as 4096 meshes (whole frames 513 against 595 ms there, where
// the rasterizer itself runs on the CPU; with a GPU those 45 ms alone would cap the page at
// about 20 frames a second).
import * as THREE from 'three';

// Colours are written as they are, as vdiso's renderer writes them: no colour management.
THREE.ColorManagement.enabled = false;

// vdiso's renderer clears to (0.08, 0.08, 0.09): 8-bit (20, 20, 23). The end-to-end test
// compares covered pixels with that renderer's picture, so this must be exact.
const BACKGROUND_RGB = [20, 20, 23];
const SURFACE_COLOR = new THREE.Color(0.89, 0.85, 0.76); // bone / skin
const AMBIENT = 0.15;
const SPECULAR = 0.2;
const SHININESS = 40.0;
// In device pixels, like the server's viewport: points stand for sub-pixel meta-cells.
const POINT_SIZE = 1.0;

// Lighting as vdiso's renderer gets it from OpenGL's fixed-function pipeline (io/render/renderer.cpp),
// so that the page's picture can be compared with it pixel for pixel: computed per vertex and
// clamped, a point light at the eye (local viewer), and GL's two-sided model, where a triangle
// seen from behind is lit with its normals turned round. Points have no side: their normals
// are turned towards the eye, as the renderer does. (Lit per fragment, the MRI at iso 80
// matched the renderer's picture on 98.4% of its covered pixels; lit this way, on 99.7%.)
const vertexShader = /* glsl */ `
#include <common>
#include <batching_pars_vertex>

// The normal's two i8 (u, v) as one u16, u | v << 8, not normalized (see decode.js).
attribute float octNormal;
uniform vec3 surfaceColor;
uniform float ambient;
uniform float specular;
uniform float shininess;
varying vec3 vFrontColor;
varying vec3 vBackColor;
#ifdef POINTS
uniform float pointSize;
#endif

// Octahedral normal, as docs/protocol.md defines it.
vec3 decodeOctahedral(float packed) {
  vec2 bytes = vec2(mod(packed, 256.0), floor(packed / 256.0));
  vec2 e = clamp((bytes - step(128.0, bytes) * 256.0) / 127.0, -1.0, 1.0);
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) {
    n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  }
  return normalize(n);
}

// The light is at the eye, so the light direction and the half vector are both the direction
// to the eye: cosine is dot(normal, toEye).
vec3 lit(float cosine) {
  vec3 color = surfaceColor * (ambient + (1.0 - ambient) * max(cosine, 0.0));
  if (cosine > 0.0) color += specular * pow(cosine, shininess);
  return min(color, 1.0);
}

void main() {
  vec4 local = vec4(position, 1.0);
#include <batching_vertex>
#ifdef USE_BATCHING
  local = batchingMatrix * local;
#endif
  vec4 viewPosition = modelViewMatrix * local;
  // Normals are in world space already: the chunk's box maps positions only.
  vec3 normal = normalize(mat3(viewMatrix) * decodeOctahedral(octNormal));
  float cosine = dot(normal, normalize(-viewPosition.xyz));
#ifdef POINTS
  vFrontColor = lit(abs(cosine));
  gl_PointSize = pointSize;
#else
  vFrontColor = lit(cosine);
#endif
  vBackColor = lit(-cosine);
  gl_Position = projectionMatrix * viewPosition;
}
`;

// Triangles are counter-clockwise seen from the side their normals point to (the protocol's
// mesh contract), so the front face is the lit side; points are always front-facing.
const fragmentShader = /* glsl */ `
varying vec3 vFrontColor;
varying vec3 vBackColor;

void main() {
  gl_FragColor = vec4(gl_FrontFacing ? vFrontColor : vBackColor, 1.0);
}
`;

function surfaceMaterial(defines = {}) {
  return new THREE.ShaderMaterial({
    vertexShader,
    fragmentShader,
    defines,
    side: THREE.DoubleSide,
    uniforms: {
      surfaceColor: { value: SURFACE_COLOR },
      ambient: { value: AMBIENT },
      specular: { value: SPECULAR },
      shininess: { value: SHININESS },
      pointSize: { value: POINT_SIZE },
    },
  });
}

// Normalized u16 positions lie in the unit cube; the instance or object matrix places it.
const UNIT_BOX = new THREE.Box3(new THREE.Vector3(0, 0, 0), new THREE.Vector3(1, 1, 1));
const UNIT_SPHERE = UNIT_BOX.getBoundingSphere(new THREE.Sphere());

function boxMatrix(boxMin, boxMax) {
  return new THREE.Matrix4()
    .makeScale(boxMax[0] - boxMin[0], boxMax[1] - boxMin[1], boxMax[2] - boxMin[2])
    .setPosition(boxMin[0], boxMin[1], boxMin[2]);
}

// Every chunk's triangles in one BatchedMesh, which has fixed capacities: they double when
// full, and the holes that removed chunks leave are compacted away once they are a quarter
// of what is allocated (BatchedMesh reuses ids, not space).
class TriangleBatch {
  constructor(material) {
    this.vertexCapacity = 1 << 18;
    this.indexCapacity = 1 << 20;
    this.instanceCapacity = 1024;
    this.liveVertices = 0;
    this.liveIndices = 0;
    this.liveInstances = 0;
    this.mesh = new THREE.BatchedMesh(this.instanceCapacity, this.vertexCapacity, this.indexCapacity, material);
    // The batch as a whole is never culled (its bounds would go stale as chunks arrive); each
    // chunk is culled and sorted front to back on its unit-cube bounds, which cost nothing.
    this.mesh.frustumCulled = false;
    this.mesh.perObjectFrustumCulled = true;
    this.mesh.sortObjects = true;
  }

  // Adds a chunk's decoded triangles (decode.js) in its box; returns its handle.
  add({ positions, normals, indices }, boxMin, boxMax) {
    const vertexCount = normals.length;
    this.reserve(vertexCount, indices.length);
    const carrier = new THREE.BufferGeometry();
    carrier.setAttribute('position', new THREE.BufferAttribute(positions, 3, true));
    carrier.setAttribute('octNormal', new THREE.BufferAttribute(normals, 1, false));
    carrier.setIndex(new THREE.BufferAttribute(indices, 1));
    carrier.boundingBox = UNIT_BOX;
    carrier.boundingSphere = UNIT_SPHERE;
    const geometryId = this.mesh.addGeometry(carrier);
    const instanceId = this.mesh.addInstance(geometryId);
    this.mesh.setMatrixAt(instanceId, boxMatrix(boxMin, boxMax));
    this.liveVertices += vertexCount;
    this.liveIndices += indices.length;
    this.liveInstances += 1;
    return { geometryId, instanceId, vertexCount, indexCount: indices.length };
  }

  remove(handle) {
    this.mesh.deleteGeometry(handle.geometryId); // deletes its instance too
    this.liveVertices -= handle.vertexCount;
    this.liveIndices -= handle.indexCount;
    this.liveInstances -= 1;
  }

  setVisible(handle, visible) {
    this.mesh.setVisibleAt(handle.instanceId, visible);
  }

  reserve(vertexCount, indexCount) {
    const mesh = this.mesh;
    if (this.liveInstances >= this.instanceCapacity) {
      this.instanceCapacity *= 2;
      mesh.setInstanceCount(this.instanceCapacity);
    }
    const fits = () => mesh.unusedVertexCount >= vertexCount && mesh.unusedIndexCount >= indexCount;
    if (fits()) return;
    const deadVertices = this.vertexCapacity - mesh.unusedVertexCount - this.liveVertices;
    const deadIndices = this.indexCapacity - mesh.unusedIndexCount - this.liveIndices;
    if (deadVertices >= this.vertexCapacity / 4 || deadIndices >= this.indexCapacity / 4) {
      mesh.optimize();
      if (fits()) return;
    }
    const vertexEnd = this.vertexCapacity - mesh.unusedVertexCount;
    const indexEnd = this.indexCapacity - mesh.unusedIndexCount;
    this.vertexCapacity = Math.max(this.vertexCapacity, 2 * (vertexEnd + vertexCount));
    this.indexCapacity = Math.max(this.indexCapacity, 2 * (indexEnd + indexCount));
    mesh.setGeometrySize(this.vertexCapacity, this.indexCapacity);
  }
}

// Near and far planes as the server's fitClipPlanes (core/camera.cpp): the nearest and
// farthest depths of the bounds' 8 corners along the view direction, widened by 1%, near at
// least far / 1000.
export function fitClipPlanes(camera, target, boundsMin, boundsMax) {
  const forward = new THREE.Vector3().subVectors(target, camera.position).normalize();
  const corner = new THREE.Vector3();
  let nearest = Infinity;
  let farthest = -Infinity;
  for (let i = 0; i < 8; ++i) {
    corner.set(i & 1 ? boundsMax[0] : boundsMin[0], i & 2 ? boundsMax[1] : boundsMin[1], i & 4 ? boundsMax[2] : boundsMin[2]);
    const depth = corner.sub(camera.position).dot(forward);
    nearest = Math.min(nearest, depth);
    farthest = Math.max(farthest, depth);
  }
  const diagonal = Math.hypot(boundsMax[0] - boundsMin[0], boundsMax[1] - boundsMin[1], boundsMax[2] - boundsMin[2]);
  const scale = Math.max(diagonal, camera.position.distanceTo(target));
  camera.far = Math.max(farthest * 1.01, scale * 0.01);
  camera.near = Math.max(nearest * 0.99, camera.far / 1000);
  camera.updateProjectionMatrix();
}

export class SurfaceScene {
  constructor(canvas) {
    // No antialiasing: vdiso's renderer has none, and the end-to-end test compares coverage.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: false, powerPreference: 'high-performance' });
    this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.renderer.setClearColor(new THREE.Color(...BACKGROUND_RGB.map((c) => c / 255)), 1);
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(30, 1, 0.1, 1000);
    this.triangles = new TriangleBatch(surfaceMaterial());
    this.scene.add(this.triangles.mesh);
    this.pointsMaterial = surfaceMaterial({ POINTS: '' });
    this.resize();
  }

  // The drawing buffer's size in device pixels: the viewport the server is told about.
  drawingBufferSize() {
    return this.renderer.getDrawingBufferSize(new THREE.Vector2());
  }

  // Fits the canvas to the window; returns whether the drawing buffer changed size.
  resize() {
    const before = this.drawingBufferSize();
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.setSize(window.innerWidth, window.innerHeight);
    const size = this.drawingBufferSize();
    this.camera.aspect = size.x / size.y;
    this.camera.updateProjectionMatrix();
    return !size.equals(before);
  }

  // Points of a chunk, interleaved as decoded (decode.js), in their box; returns the object.
  addPoints(vertices, boxMin, boxMax) {
    const interleaved = new THREE.InterleavedBuffer(vertices, 4);
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.InterleavedBufferAttribute(interleaved, 3, 0, true));
    geometry.setAttribute('octNormal', new THREE.InterleavedBufferAttribute(interleaved, 1, 3, false));
    geometry.boundingBox = UNIT_BOX.clone();
    geometry.boundingSphere = UNIT_SPHERE.clone();
    const points = new THREE.Points(geometry, this.pointsMaterial);
    points.matrixAutoUpdate = false;
    points.matrix.copy(boxMatrix(boxMin, boxMax));
    this.scene.add(points);
    return points;
  }

  removePoints(points) {
    this.scene.remove(points);
    points.geometry.dispose();
  }

  render() {
    this.renderer.render(this.scene, this.camera);
  }
}
