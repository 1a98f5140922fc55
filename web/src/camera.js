// The camera as the server sees it ({eye, target, up, fov}: world coordinates, vertical field
// of view in degrees, as `vdiso extract --camera`), the distant/normal/closeup presets of
// vdiso's core, and orbit/pan/zoom with three.js's OrbitControls.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const PRESET_NAMES = ['distant', 'normal', 'closeup'];

// Exactly core/camera.cpp's presetCamera (see its header for what each view is). `facing` is
// the store's (hello: toEye, up, front; anterior for a store with orientation); without one,
// core's defaultFacing().
const DEFAULT_FACING = { toEye: new THREE.Vector3(0.35, 1.0, 0.3).normalize().toArray(), up: [0, 0, 1], front: [0, 1, 0] };
const PRESET_FOV = 30;
const DISTANT_IMAGE_FRACTION = 0.1;
const CLOSEUP_LOOK_AT_FRONT = 0.35;
const CLOSEUP_FRACTION = 1 / 6;

export function presetCamera(name, boundsMin, boundsMax, aspect, facing = DEFAULT_FACING) {
  const b0 = new THREE.Vector3(...boundsMin);
  const b1 = new THREE.Vector3(...boundsMax);
  const centre = b0.clone().add(b1).multiplyScalar(0.5);
  const extent = b1.clone().sub(b0);
  const radius = Math.max(0.5 * extent.length(), 1e-6);
  const tanHalf = Math.tan(THREE.MathUtils.degToRad(PRESET_FOV) * 0.5);
  const halfFit = Math.atan(tanHalf * Math.min(1, aspect));
  let target = centre;
  let distance;
  if (name === 'normal') {
    distance = radius / Math.sin(halfFit);
  } else if (name === 'distant') {
    distance = radius / Math.sin(Math.atan(DISTANT_IMAGE_FRACTION * tanHalf));
  } else if (name === 'closeup') {
    const front = new THREE.Vector3(...facing.front);
    const depth = Math.abs(front.x) * extent.x + Math.abs(front.y) * extent.y + Math.abs(front.z) * extent.z;
    target = centre.clone().addScaledVector(front, CLOSEUP_LOOK_AT_FRONT * depth);
    const largest = Math.max(extent.x, extent.y, extent.z, 1e-6);
    distance = (0.5 * CLOSEUP_FRACTION * largest) / tanHalf;
  } else {
    throw new Error(`unknown view preset '${name}' (expected ${PRESET_NAMES.join(', ')})`);
  }
  const eye = target.clone().addScaledVector(new THREE.Vector3(...facing.toEye), distance);
  return { eye: eye.toArray(), target: target.toArray(), up: [...facing.up], fov: PRESET_FOV };
}

function checkVec3(name, value) {
  if (!Array.isArray(value) || value.length !== 3 || !value.every(Number.isFinite)) {
    throw new Error(`camera ${name} must be 3 finite numbers, got ${JSON.stringify(value)}`);
  }
}

// Throws unless the server would accept the camera (docs/protocol.md, VIEW).
function checkCamera({ eye, target, up, fov }) {
  checkVec3('eye', eye);
  checkVec3('target', target);
  checkVec3('up', up);
  if (!(fov > 0 && fov < 180)) throw new Error(`camera fov must be in (0, 180) degrees, got ${fov}`);
  const forward = new THREE.Vector3(...target).sub(new THREE.Vector3(...eye));
  if (forward.lengthSq() === 0) throw new Error('camera eye and target must differ');
  // The server's test (serve/protocol.cpp): unit vectors whose cross product is under 1e-9.
  const side = forward.normalize().cross(new THREE.Vector3(...up).normalize());
  if (!(side.length() >= 1e-9)) throw new Error('camera up must not be parallel to target - eye');
}

// Owns the three.js camera's placement: OrbitControls for the user, set() for scripts and
// presets. onChange() is called whenever the camera moved.
export class CameraController {
  constructor(camera, domElement, onChange) {
    this.camera = camera;
    this.domElement = domElement;
    this.onChange = onChange;
    this.controls = null;
    this.up = null;
    this.enabled = true;
  }

  // A follower's camera is its leader's: the user's drags do nothing then.
  setEnabled(enabled) {
    this.enabled = enabled;
    if (this.controls) this.controls.enabled = enabled;
  }

  get() {
    return {
      eye: this.camera.position.toArray(),
      target: this.controls.target.toArray(),
      up: [...this.up],
      fov: this.camera.fov,
    };
  }

  target() {
    return this.controls.target;
  }

  // Places the camera exactly as given: the numbers sent to the server are these.
  set(camera) {
    checkCamera(camera);
    const { eye, target, up, fov } = camera;
    // OrbitControls orbits about the camera's up as it was when they were made.
    if (!this.up || !up.every((c, i) => c === this.up[i])) {
      this.controls?.dispose();
      this.camera.up.set(...up);
      this.controls = new OrbitControls(this.camera, this.domElement);
      // Short of the poles by a margin: at OrbitControls' own clamp (1e-6 rad) the view is
      // parallel to up within rounding, a camera the server refuses.
      this.controls.minPolarAngle = 1e-3;
      this.controls.maxPolarAngle = Math.PI - 1e-3;
      this.controls.addEventListener('change', () => this.onChange());
      this.controls.enabled = this.enabled;
      this.up = [...up];
    }
    this.camera.fov = fov;
    this.camera.position.set(...eye);
    this.controls.target.set(...target);
    this.camera.lookAt(this.controls.target);
    this.camera.updateProjectionMatrix();
    this.onChange();
  }
}
