// The die in the studio's 3D scene: one group of flat faces, each with its color, edges and printed value.
//
// `show(data)` redraws it from the server's data (see diefab/studio/scene.py, `die_data`):
//   vertices: (n, 3) model units; faces: lists of vertex indices (convex, counter-clockwise from outside);
//   colors: one CSS color per face; labels: one text per face ("" for none);
//   quads: per face the label's corners [top-left, top-right, bottom-left, bottom-right];
//   mesh: optional, the body as made (its values engraved or embossed), drawn instead of the flat faces:
//   {vertices: (n, 3), triangles: (t, 3), face_of: (t,) face of each triangle, engraved: (t,) 0/1 label triangles}.
// `paint(colors)` only recolors the faces (a hover or a selection).
import { THREE } from "nicegui-scene";

const LABEL_PX = 128;
const WHITE = new THREE.Color("#ffffff");

function labelTexture(text) {
  const canvas = document.createElement("canvas");
  canvas.width = canvas.height = LABEL_PX;
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#fbf8ef";
  ctx.fillRect(0, 0, LABEL_PX, LABEL_PX);
  ctx.fillStyle = "#141414";
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  let size = LABEL_PX;
  do {
    ctx.font = `bold ${size}px sans-serif`;
    size -= 4;
  } while (size > 8 && ctx.measureText(text).width > 0.9 * LABEL_PX);
  ctx.fillText(text, LABEL_PX / 2, LABEL_PX / 2 + 0.04 * LABEL_PX);
  const texture = new THREE.CanvasTexture(canvas);
  texture.colorSpace = THREE.SRGBColorSpace;
  return texture;
}

export default class Die {
  create_mesh(data) {
    this.group = new THREE.Group();
    this.textures = new Map();
    this.show(data);
    return this.group;
  }

  texture(text) {
    if (!this.textures.has(text)) this.textures.set(text, labelTexture(text));
    return this.textures.get(text);
  }

  clear() {
    for (const child of [...this.group.children]) {
      child.geometry?.dispose();
      child.material?.dispose(); // a label's texture is kept: it is shared by every face with that text
      this.group.remove(child);
    }
  }

  show(data) {
    this.clear();
    this.faces = [];
    this.body = null;
    if (data.mesh) {
      this.showMesh(data); // the made body's own edges and engraving show its shape and values
      return;
    }
    const v = data.vertices;
    data.faces.forEach((face, k) => {
      const positions = [];
      for (let i = 1; i + 1 < face.length; i++) positions.push(...v[face[0]], ...v[face[i]], ...v[face[i + 1]]);
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.Float32BufferAttribute(positions, 3));
      geometry.computeVertexNormals();
      const material = new THREE.MeshPhongMaterial({ color: data.colors[k], flatShading: true, side: THREE.DoubleSide,
        polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
      const mesh = new THREE.Mesh(geometry, material);
      this.group.add(mesh);
      this.faces.push(mesh);
    });
    const edges = [];
    data.faces.forEach((face) => face.forEach((a, i) => edges.push(...v[a], ...v[face[(i + 1) % face.length]])));
    const lines = new THREE.BufferGeometry();
    lines.setAttribute("position", new THREE.Float32BufferAttribute(edges, 3));
    this.group.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: "#333333" })));
    data.labels.forEach((text, k) => {
      if (!text) return;
      const q = data.quads[k];
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.Float32BufferAttribute([...q[0], ...q[1], ...q[2], ...q[3]], 3));
      geometry.setAttribute("uv", new THREE.Float32BufferAttribute([0, 1, 1, 1, 0, 0, 1, 0], 2));
      geometry.setIndex([0, 2, 1, 1, 2, 3]);
      const material = new THREE.MeshBasicMaterial({ map: this.texture(text) });
      this.group.add(new THREE.Mesh(geometry, material));
    });
  }

  showMesh(data) {
    const { vertices, triangles, face_of, engraved } = data.mesh;
    const positions = new Float32Array(9 * triangles.length);
    triangles.forEach((tri, t) => tri.forEach((i, j) => positions.set(vertices[i], 9 * t + 3 * j)));
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    this.faceOf = face_of;
    this.engraved = engraved;
    this.meshColors = new Float32Array(positions.length);
    geometry.setAttribute("color", new THREE.BufferAttribute(this.meshColors, 3));
    const material = new THREE.MeshPhongMaterial({ vertexColors: true, flatShading: true, side: THREE.DoubleSide });
    this.body = new THREE.Mesh(geometry, material);
    this.group.add(this.body);
    this.paint(data.colors);
  }

  paint(colors) {
    if (this.body) {
      const c = new THREE.Color();
      this.faceOf.forEach((k, t) => {
        c.set(colors[k]);
        if (this.engraved[t]) {
          // the label's walls and floor: darker than a light face, lighter than a dark one, so the value reads
          const luminance = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
          if (luminance > 0.12) c.multiplyScalar(0.3);
          else c.lerp(WHITE, 0.55);
        }
        for (let j = 0; j < 3; j++) this.meshColors.set([c.r, c.g, c.b], 9 * t + 3 * j);
      });
      this.body.geometry.attributes.color.needsUpdate = true;
      return;
    }
    this.faces.forEach((mesh, k) => mesh.material.color.set(colors[k]));
  }
}
