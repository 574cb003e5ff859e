// The 3D view of multicue's report.html. The page embeds its data as JSON in
// <script type="application/json" id="mc-data">: the point cloud quantised to 16 bits per
// coordinate, per-point colour, object, category and part as base64 typed arrays, and one mesh per
// reconstructed model. The object list beside the view is plain HTML written by multicue; this
// script only adds the view, the colouring buttons and selection.

import {
    AmbientLight,
    Box3,
    Box3Helper,
    BufferAttribute,
    BufferGeometry,
    Color,
    ColorManagement,
    DirectionalLight,
    DoubleSide,
    Group,
    HemisphereLight,
    LineBasicMaterial,
    LineLoop,
    LinearSRGBColorSpace,
    Mesh,
    MeshBasicMaterial,
    MeshLambertMaterial,
    PerspectiveCamera,
    Points,
    PointsMaterial,
    Raycaster,
    Scene,
    Vector2,
    Vector3,
    WebGLRenderer,
} from 'three';
import {OrbitControls} from 'three/examples/jsm/controls/OrbitControls.js';

const BACKGROUND = 0x1b1f24;
// Colours are shown as given (sensor RGB, the object colours of models.ply, the legend's): no
// sRGB-to-linear round trip, which would wash out the sensor's colours and the dimming.
ColorManagement.enabled = false;
const NO_OBJECT_GREY = [0.55, 0.56, 0.58];

function decode(b64, Type) {
    if (!b64) return null;
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
}

function hexToRgb(hex) {
    const c = new Color(hex);
    return [c.r, c.g, c.b];
}

// Distinct, stable colours for part ids (golden-angle hues).
function partColor(id) {
    if (id === 0) return NO_OBJECT_GREY;
    const c = new Color();
    c.setHSL(((id * 137.508) % 360) / 360, 0.65, 0.55);
    return [c.r, c.g, c.b];
}

class ReportViewer {
    constructor(data, container) {
        this.data = data;
        this.container = container;
        this.mode = data.cloud && data.cloud.colors ? 'rgb' : 'object';
        this.selected = 0;
        this.objectColors = new Map(data.objects.map((o) => [o.id, hexToRgb(o.color)]));
        this.categoryColors = data.category_colors.map(hexToRgb);

        this.renderer = new WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
        this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
        this.renderer.outputColorSpace = LinearSRGBColorSpace;
        this.renderer.setClearColor(BACKGROUND, 1);
        container.appendChild(this.renderer.domElement);

        this.scene = new Scene();
        // Ambient, a sky light from above (placed along up in placeCamera) and a head light, so that
        // the tops and the sides of the models both read.
        this.scene.add(new AmbientLight(0xffffff, 0.9));
        this.sky = new HemisphereLight(0xffffff, 0x444444, 1.2);
        this.scene.add(this.sky);
        this.light = new DirectionalLight(0xffffff, 1.2);
        this.scene.add(this.light);

        this.buildCloud();
        this.buildModels();
        this.buildSupport();
        this.placeCamera();
        this.bindEvents();
        this.resize();
        this.setMode(this.mode);
    }

    buildCloud() {
        const cloud = this.data.cloud;
        const n = cloud.count;
        const q = decode(cloud.positions, Uint16Array);
        const positions = new Float32Array(n * 3);
        const o = cloud.origin;
        const s = cloud.scale;
        for (let i = 0; i < n; ++i) {
            for (let k = 0; k < 3; ++k) positions[3 * i + k] = o[k] + q[3 * i + k] * s[k];
        }
        this.positions = positions;
        this.rgb = decode(cloud.colors, Uint8Array);
        this.pointObjects = cloud.object_bytes === 2 ? decode(cloud.objects, Uint16Array)
                                                      : decode(cloud.objects, Uint8Array);
        this.pointCategories = decode(cloud.categories, Uint8Array);
        this.pointParts = decode(cloud.parts, Uint16Array);

        const geometry = new BufferGeometry();
        geometry.setAttribute('position', new BufferAttribute(positions, 3));
        this.colorBuffer = new Uint8Array(n * 3);
        geometry.setAttribute('color', new BufferAttribute(this.colorBuffer, 3, true));
        geometry.computeBoundingSphere();
        this.pointSize = cloud.point_size;
        this.cloudMaterial = new PointsMaterial({size: this.pointSize, vertexColors: true});
        this.cloud = new Points(geometry, this.cloudMaterial);
        this.scene.add(this.cloud);
    }

    buildModels() {
        this.models = new Group();
        this.modelMeshes = new Map();
        for (const obj of this.data.objects) {
            if (!obj.mesh) continue;
            const vertices = decode(obj.mesh.vertices, Float32Array);
            const triangles = decode(obj.mesh.triangles, Uint32Array);
            if (!vertices || !triangles || triangles.length === 0) continue;
            const geometry = new BufferGeometry();
            geometry.setAttribute('position', new BufferAttribute(vertices, 3));
            geometry.setIndex(new BufferAttribute(triangles, 1));
            geometry.computeVertexNormals();
            const material = new MeshLambertMaterial({
                color: new Color(obj.color),
                transparent: true,
                opacity: 0.55,
                side: DoubleSide,
                depthWrite: false,
            });
            const mesh = new Mesh(geometry, material);
            mesh.userData.objectId = obj.id;
            this.models.add(mesh);
            this.modelMeshes.set(obj.id, mesh);
        }
        this.scene.add(this.models);
    }

    buildSupport() {
        this.support = new Group();
        const support = this.data.support;
        if (support && support.hull && support.hull.length >= 3) {
            const hull = support.hull;
            // The hull is convex: a triangle fan covers it.
            const vertices = new Float32Array(hull.flat());
            const index = [];
            for (let i = 1; i + 1 < hull.length; ++i) index.push(0, i, i + 1);
            const geometry = new BufferGeometry();
            geometry.setAttribute('position', new BufferAttribute(vertices, 3));
            geometry.setIndex(index);
            this.support.add(new Mesh(geometry, new MeshBasicMaterial({
                color: 0x4fa3d9, transparent: true, opacity: 0.25, side: DoubleSide,
                depthWrite: false,
            })));
            const outline = new BufferGeometry();
            outline.setAttribute('position', new BufferAttribute(vertices.slice(), 3));
            this.support.add(new LineLoop(outline, new LineBasicMaterial({color: 0x7cc4f0})));
        }
        this.scene.add(this.support);
    }

    placeCamera() {
        const up = new Vector3().fromArray(this.data.up);
        const sphere = this.cloud.geometry.boundingSphere;
        // Look at the objects when there are any, else at the whole cloud.
        const target = new Vector3();
        if (this.data.objects.length > 0) {
            for (const obj of this.data.objects) target.add(new Vector3().fromArray(obj.centroid));
            target.divideScalar(this.data.objects.length);
        } else {
            target.copy(sphere.center);
        }
        const eye = new Vector3().fromArray(this.data.sensor_origin);
        if (eye.distanceTo(target) < 1e-3) eye.copy(target).add(new Vector3(0, 0, -sphere.radius));
        // Start from the sensor, raised a little along up, so the table top is seen at an angle.
        const dist = eye.distanceTo(target);
        eye.addScaledVector(up, 0.25 * dist);
        this.camera = new PerspectiveCamera(50, 1, Math.max(dist * 0.01, 1e-3), dist * 50 + 10);
        this.camera.up.copy(up);
        this.sky.position.copy(up);
        this.camera.position.copy(eye);
        this.controls = new OrbitControls(this.camera, this.renderer.domElement);
        this.controls.target.copy(target);
        this.controls.update();
        this.controls.addEventListener('change', () => this.render());
        this.home = {eye: eye.clone(), target: target.clone()};
    }

    resetView() {
        this.camera.position.copy(this.home.eye);
        this.controls.target.copy(this.home.target);
        this.controls.update();
        this.render();
    }

    pointColor(i) {
        const id = this.pointObjects[i];
        switch (this.mode) {
            case 'rgb':
                if (this.rgb) {
                    return [this.rgb[3 * i] / 255, this.rgb[3 * i + 1] / 255,
                            this.rgb[3 * i + 2] / 255];
                }
                return NO_OBJECT_GREY;
            case 'object':
                return id ? this.objectColors.get(id) || NO_OBJECT_GREY : NO_OBJECT_GREY;
            case 'category': {
                const c = this.pointCategories[i];
                return c ? this.categoryColors[c] : NO_OBJECT_GREY;
            }
            default:
                return partColor(this.pointParts[i]);
        }
    }

    recolor() {
        const n = this.data.cloud.count;
        const sel = this.selected;
        for (let i = 0; i < n; ++i) {
            let [r, g, b] = this.pointColor(i);
            // A selection dims everything else.
            if (sel && this.pointObjects[i] !== sel) {
                r *= 0.3;
                g *= 0.3;
                b *= 0.3;
            }
            this.colorBuffer[3 * i] = Math.round(r * 255);
            this.colorBuffer[3 * i + 1] = Math.round(g * 255);
            this.colorBuffer[3 * i + 2] = Math.round(b * 255);
        }
        this.cloud.geometry.attributes.color.needsUpdate = true;
        for (const [id, mesh] of this.modelMeshes) {
            // Lighter over the sensor's colours, which the models would otherwise tint.
            const base = this.mode === 'rgb' ? 0.3 : 0.55;
            mesh.material.opacity = !sel ? base : id === sel ? 0.85 : 0.12;
        }
        this.render();
    }

    setMode(mode) {
        this.mode = mode;
        document.querySelectorAll('[data-color-mode]').forEach((b) => {
            b.classList.toggle('active', b.dataset.colorMode === mode);
        });
        document.querySelectorAll('[data-legend]').forEach((l) => {
            l.hidden = l.dataset.legend !== mode;
        });
        this.recolor();
    }

    select(id) {
        this.selected = id;
        document.querySelectorAll('[data-object]').forEach((el) => {
            el.classList.toggle('selected', Number(el.dataset.object) === id);
        });
        if (this.boxHelper) {
            this.scene.remove(this.boxHelper);
            this.boxHelper = null;
        }
        if (id) {
            const box = new Box3();
            const p = new Vector3();
            for (let i = 0; i < this.data.cloud.count; ++i) {
                if (this.pointObjects[i] === id) box.expandByPoint(p.fromArray(this.positions, 3 * i));
            }
            if (!box.isEmpty()) {
                this.boxHelper = new Box3Helper(box, new Color(0xffffff));
                this.scene.add(this.boxHelper);
            }
            const row = document.querySelector(`[data-object="${id}"]`);
            if (row && row.scrollIntoView) row.scrollIntoView({block: 'nearest'});
        }
        this.recolor();
    }

    pick(event) {
        const rect = this.renderer.domElement.getBoundingClientRect();
        const ndc = new Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                -((event.clientY - rect.top) / rect.height) * 2 + 1);
        const ray = new Raycaster();
        ray.params.Points.threshold = this.pointSize * 1.5;
        ray.setFromCamera(ndc, this.camera);
        const targets = [];
        if (this.models.visible) targets.push(...this.models.children);
        if (this.cloud.visible) targets.push(this.cloud);
        for (const hit of ray.intersectObjects(targets, false)) {
            const id = hit.object === this.cloud ? this.pointObjects[hit.index]
                                                 : hit.object.userData.objectId;
            if (id) return id;
        }
        return 0;
    }

    bindEvents() {
        document.querySelectorAll('[data-color-mode]').forEach((b) => {
            b.addEventListener('click', () => this.setMode(b.dataset.colorMode));
        });
        const toggles = {cloud: this.cloud, models: this.models, support: this.support};
        document.querySelectorAll('[data-toggle]').forEach((box) => {
            const target = toggles[box.dataset.toggle];
            if (!target) return;
            target.visible = box.checked;
            box.addEventListener('change', () => {
                target.visible = box.checked;
                this.render();
            });
        });
        const size = document.getElementById('mc-point-size');
        if (size) {
            size.addEventListener('input', () => {
                this.cloudMaterial.size = this.pointSize * Number(size.value);
                this.render();
            });
        }
        const reset = document.getElementById('mc-reset-view');
        if (reset) reset.addEventListener('click', () => this.resetView());
        document.querySelectorAll('[data-object]').forEach((el) => {
            el.addEventListener('click', () => {
                const id = Number(el.dataset.object);
                this.select(this.selected === id ? 0 : id);
            });
        });
        // A click (not a drag) in the view picks the object under the pointer.
        let down = null;
        const canvas = this.renderer.domElement;
        canvas.addEventListener('pointerdown', (e) => (down = [e.clientX, e.clientY]));
        canvas.addEventListener('pointerup', (e) => {
            if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) {
                this.select(this.pick(e));
            }
            down = null;
        });
        window.addEventListener('resize', () => this.resize());
    }

    resize() {
        const w = Math.max(this.container.clientWidth, 1);
        const h = Math.max(this.container.clientHeight, 1);
        this.renderer.setSize(w, h, false);
        this.renderer.domElement.style.width = '100%';
        this.renderer.domElement.style.height = '100%';
        this.camera.aspect = w / h;
        this.camera.updateProjectionMatrix();
        this.render();
    }

    render() {
        this.light.position.copy(this.camera.position);
        this.renderer.render(this.scene, this.camera);
    }
}

function start() {
    const state = {ready: false, error: null, objects: [], loadMs: null};
    window.multicueReport = state;
    try {
        const el = document.getElementById('mc-data');
        const container = document.getElementById('mc-view');
        if (!el || !container) return;
        const t0 = performance.now();
        const data = JSON.parse(el.textContent);
        const t1 = performance.now();
        state.objects = data.objects.map((o) => o.id);
        if (!data.cloud) {
            container.classList.add('mc-no-view');
        } else {
            state.viewer = new ReportViewer(data, container);
        }
        state.loadMs = performance.now();
        // Where the time goes: page parsing until this script ran, JSON, building and first frame.
        state.timings = {before_script: t0, json: t1 - t0, viewer: state.loadMs - t1};
        state.ready = true;
    } catch (err) {
        state.error = String(err);
        const view = document.getElementById('mc-view');
        if (view) {
            const note = document.createElement('p');
            note.className = 'mc-error';
            note.textContent = `The 3D view could not start: ${err.message || err}`;
            view.appendChild(note);
        }
        throw err;
    }
}

if (document.readyState === 'loading') {
    document.addEventListener('DOMContentLoaded', start);
} else {
    start();
}
