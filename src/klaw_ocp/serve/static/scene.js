// The 3D view: the 37-joint body as bones, the ground grid, the footprints, an orbit camera and a
// follow camera. World frame as the server sends it: x forward, y up, z to the right (m).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const LEG_COLOURS = { right: 0x0072b2, left: 0xcc79a7 };   // the plots' leg colours (figures/plot_style.py)
const MAX_FOOTPRINTS = 40;

export class Scene {
  constructor(canvas) {
    this.canvas = canvas;
    // preserveDrawingBuffer: a screenshot (the browser test's) sees the last frame drawn
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xdfe6ea);
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.05, 200);
    this.camera.position.set(1.2, 1.4, 4.2);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.target.set(0, 0.9, 0);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(3, 6, 4);
    this.scene.add(sun);
    // the ground: a plane with a 0.5 m grid on it, 40 m square, moved with the body in whole
    // grid cells (so the lines stand still under the feet)
    this.ground = new THREE.Group();
    const plane = new THREE.Mesh(new THREE.PlaneGeometry(40, 40), new THREE.MeshStandardMaterial({ color: 0xc9d3c4, roughness: 1 }));
    plane.rotation.x = -Math.PI / 2;
    plane.position.y = -0.01;
    const grid = new THREE.GridHelper(40, 80, 0x55656f, 0x8d9ba1);
    grid.position.y = 0.001;
    this.ground.add(plane, grid);
    this.scene.add(this.ground);
    this.follow = true;
    this.bones = [];
    this.footprints = [];
    this.lastRootX = 0;
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  resize() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    if (!w || !h) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  // the bones of the skeleton message: each joint to its parent, each end site to its joint
  setSkeleton(skeleton) {
    for (const bone of this.bones) this.scene.remove(bone.mesh);
    if (this.head) this.scene.remove(this.head.mesh);
    this.bones = [];
    const names = skeleton.joints, n = names.length;
    const colour = (name) => name.startsWith("r_") ? LEG_COLOURS.right : name.startsWith("l_") ? LEG_COLOURS.left : 0x444444;
    const add = (a, b, name, radius) => {
      const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 8),
                                  new THREE.MeshStandardMaterial({ color: colour(name), roughness: 0.6 }));
      this.scene.add(mesh);
      this.bones.push({ a, b, mesh });
    };
    skeleton.parents.forEach((p, i) => { if (p >= 0) add(p, i, names[i], 0.022); });
    skeleton.end_sites.forEach((joint, k) => add(joint, n + k, names[joint], 0.018));
    // the head: a sphere between the top of the neck (C1) and the head's top
    const c1 = names.indexOf("C1"), top = n + skeleton.end_sites.indexOf(c1);
    this.head = { a: c1, b: top, mesh: new THREE.Mesh(new THREE.SphereGeometry(0.1, 16, 12),
                                                    new THREE.MeshStandardMaterial({ color: 0x444444, roughness: 0.6 })) };
    this.scene.add(this.head.mesh);
    for (const f of this.footprints) this.scene.remove(f);
    this.footprints = [];
  }

  addFootprint(foot, side) {
    const mesh = new THREE.Mesh(new THREE.BoxGeometry(0.26, 0.004, 0.09),
                                new THREE.MeshStandardMaterial({ color: LEG_COLOURS[side], transparent: true, opacity: 0.55 }));
    mesh.position.set(foot.x + 0.07, 0.004, foot.z);
    this.scene.add(mesh);
    this.footprints.push(mesh);
    if (this.footprints.length > MAX_FOOTPRINTS) this.scene.remove(this.footprints.shift());
  }

  // one frame: points is the flat [x, y, z, ...] of the joints then the end sites
  pose(points) {
    const up = new THREE.Vector3(0, 1, 0), a = new THREE.Vector3(), b = new THREE.Vector3(), d = new THREE.Vector3();
    for (const bone of this.bones) {
      a.fromArray(points, 3 * bone.a);
      b.fromArray(points, 3 * bone.b);
      d.subVectors(b, a);
      const length = d.length();
      bone.mesh.position.addVectors(a, b).multiplyScalar(0.5);
      bone.mesh.scale.set(1, Math.max(length, 1e-4), 1);
      if (length > 1e-9) bone.mesh.quaternion.setFromUnitVectors(up, d.divideScalar(length));
    }
    if (this.head) {
      a.fromArray(points, 3 * this.head.a); b.fromArray(points, 3 * this.head.b);
      this.head.mesh.position.addVectors(a, b).multiplyScalar(0.5);
    }
    const rootX = points[0];
    this.ground.position.x = Math.round(rootX / 0.5) * 0.5;
    if (this.follow) {
      // the follow camera keeps its offset from the pelvis as the body walks on
      const dx = rootX - this.lastRootX;
      this.camera.position.x += dx;
      this.controls.target.x += dx;
    }
    this.lastRootX = rootX;
  }

  render() {
    this.controls.update();
    this.renderer.render(this.scene, this.camera);
  }
}
