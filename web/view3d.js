// omma's 3D view of a point cloud: three.js's PLYLoader parses the PLY the page carries
// (window.omma3dCloud, set by view3d.html), drawn as coloured points; OrbitControls turns (left drag),
// zooms (wheel) and pans (right drag) around the cloud's centre. The rig frame's +z (the dome axis) is up.
// Fills window.omma3d = {ready, points, bounds: [xmin, ymin, zmin, xmax, ymax, zmax] (mm), renders,
// camera: [x, y, z], error}.
import * as THREE from 'three';
import { PLYLoader } from 'three/addons/loaders/PLYLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const status = window.omma3d;
const options = window.omma3dOptions || {};
const container = document.getElementById('view');

const geometry = new PLYLoader().parse(window.omma3dCloud.buffer);
const count = geometry.getAttribute('position').count;
geometry.computeBoundingBox();
geometry.computeBoundingSphere();
const box = geometry.boundingBox;
const centre = count > 0 ? box.getCenter(new THREE.Vector3()) : new THREE.Vector3();
const radius = count > 0 ? Math.max(geometry.boundingSphere.radius, 1e-3) : 100;

const scene = new THREE.Scene();
scene.background = new THREE.Color(0x111111);
const material = new THREE.PointsMaterial({
  size: options.pointSize || 2,
  sizeAttenuation: false,  // pixels on screen, whatever the distance
  vertexColors: geometry.hasAttribute('color'),
});
scene.add(new THREE.Points(geometry, material));
scene.add(new THREE.AxesHelper(radius * 0.25));  // the rig frame at the dome centre: x red, y green, z blue

const camera = new THREE.PerspectiveCamera(50, 1, radius / 1000, radius * 100);
camera.up.set(0, 0, 1);  // the dome axis up
// From outside the cloud, obliquely: in front of the dome (its axis +z looks forward) and a little above.
camera.position.copy(centre).add(new THREE.Vector3(1.4, -1.8, 1.2).multiplyScalar(radius));

const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
container.appendChild(renderer.domElement);

const controls = new OrbitControls(camera, renderer.domElement);
controls.target.copy(centre);
controls.enableDamping = false;  // the view follows the mouse exactly: nothing moves on its own

function render() {
  renderer.render(scene, camera);
  status.renders += 1;
  status.camera = camera.position.toArray();
}
function resize() {
  const w = container.clientWidth || 1, h = container.clientHeight || 1;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}
controls.addEventListener('change', render);
window.addEventListener('resize', resize);
controls.update();
resize();

document.getElementById('count').textContent =
    count.toLocaleString('en') + ' points' +
    (options.pointsInFile && options.pointsInFile !== count
         ? ' (one in ' + options.stride + ' of the file\'s ' + options.pointsInFile.toLocaleString('en') + ')'
         : '');
status.points = count;
status.bounds = count > 0 ? [...box.min.toArray(), ...box.max.toArray()] : null;
status.ready = true;
