// dsreg viewer: shows the layers of the page (data in #dsreg-page, binary buffers in
// #dsreg-buffer-I-J, see include/dsreg/html_view.hpp) with three.js: orbit, pan, zoom, reset;
// surface, digital surface, wireframe and feature lines; colour modes with a legend; summary.
// The URL fragment sets the state at load time (docs/viewer.md), e.g.
//   page.html#layer=2&colour=deviation&wireframe=1&digital=1&surface=0&features=0
//             &azimuth=30&elevation=20&up=+z&panels=0&background=none
(function () {
  'use strict';

  var page = JSON.parse(document.getElementById('dsreg-page').textContent);
  var root = document.documentElement;

  // ---- URL fragment options ------------------------------------------------------------------

  function readOptions() {
    var options = {};
    location.hash.replace(/^#/, '').split('&').forEach(function (pair) {
      if (!pair) return;
      var at = pair.indexOf('=');
      var key = decodeURIComponent(at < 0 ? pair : pair.slice(0, at));
      options[key] = at < 0 ? '1' : decodeURIComponent(pair.slice(at + 1));
    });
    return options;
  }
  var options = readOptions();
  function flag(name, fallback) {
    return name in options ? options[name] !== '0' && options[name] !== 'false' : fallback;
  }
  function number(name, fallback) {
    var value = Number(options[name]);
    return name in options && isFinite(value) ? value : fallback;
  }

  // ---- binary buffers ------------------------------------------------------------------------

  var arrayTypes = { float32: Float32Array, uint32: Uint32Array, int32: Int32Array };
  var decoded = [];

  // Buffer i as a typed array, decoded from its base64 chunks on first use (the text is then
  // dropped, so the page does not hold it twice).
  function buffer(index) {
    if (decoded[index]) return decoded[index];
    var meta = page.buffers[index];
    var bytes = new Uint8Array(meta.count * 4);
    var offset = 0;
    for (var chunk = 0; chunk < meta.chunks; ++chunk) {
      var element = document.getElementById('dsreg-buffer-' + index + '-' + chunk);
      var text = atob(element.textContent);
      for (var i = 0; i < text.length; ++i) bytes[offset + i] = text.charCodeAt(i);
      offset += text.length;
      element.textContent = '';
    }
    if (offset !== bytes.length) throw new Error('buffer ' + index + ': ' + offset + ' bytes, expected ' + bytes.length);
    decoded[index] = new arrayTypes[meta.type](bytes.buffer);
    return decoded[index];
  }

  // ---- colours ---------------------------------------------------------------------------------

  // Colour maps: control points [t, r, g, b] for t in [0, 1], interpolated linearly.
  var colourMaps = {
    angle: [[0, 250, 246, 205], [0.35, 246, 178, 80], [0.7, 214, 66, 42], [1, 112, 12, 24]],
    length: [[0, 236, 241, 250], [0.35, 128, 176, 222], [0.7, 42, 86, 170], [1, 16, 26, 82]],
    feature_map: [[0, 190, 22, 30], [0.5, 238, 158, 118], [1, 212, 216, 224]],
    scalar: [[0, 52, 40, 112], [0.5, 40, 150, 140], [1, 240, 226, 64]]
  };
  var plainColours = { surface: [178, 192, 212], digital: [224, 202, 160] };
  var undefinedColour = [128, 128, 128];

  function lookupTable(points) {  // 256 RGB entries
    var table = new Uint8Array(256 * 3);
    for (var i = 0; i < 256; ++i) {
      var t = i / 255, k = 1;
      while (k < points.length - 1 && points[k][0] < t) ++k;
      var a = points[k - 1], b = points[k], s = (t - a[0]) / (b[0] - a[0]);
      for (var c = 0; c < 3; ++c) table[3 * i + c] = Math.round(a[c + 1] + s * (b[c + 1] - a[c + 1]));
    }
    return table;
  }
  var tables = {};
  Object.keys(colourMaps).forEach(function (name) { tables[name] = lookupTable(colourMaps[name]); });

  function cssColour(rgb) { return 'rgb(' + rgb[0] + ',' + rgb[1] + ',' + rgb[2] + ')'; }

  // A distinct colour per integer label: hues spread by the golden angle; label 0 light grey.
  function labelColour(label) {
    if (label === 0) return [205, 205, 205];
    var hue = ((label * 0.618033988749895) % 1 + 1) % 1, s = 0.62, l = label % 2 ? 0.52 : 0.62;
    var q = l < 0.5 ? l * (1 + s) : l + s - l * s, p = 2 * l - q;
    return [hue + 1 / 3, hue, hue - 1 / 3].map(function (t) {
      t = (t + 1) % 1;
      var v = t < 1 / 6 ? p + (q - p) * 6 * t : t < 1 / 2 ? q : t < 2 / 3 ? p + (q - p) * (2 / 3 - t) * 6 : p;
      return Math.round(255 * v);
    });
  }

  // ---- colour modes of a layer -----------------------------------------------------------------

  // Each mode: key (URL), title (menu), legend, and how to colour a surface of the layer.
  function layerModes(layer) {
    var modes = [{ key: 'plain', title: 'plain', kind: 'plain' }];
    if (layer.surface.deviation)
      modes.push({ key: 'deviation', title: 'deviation from u (per face)', kind: 'angle', perFace: true,
                   field: 'deviation', legend: 'angle between each face and its normal u (degrees)',
                   range: layer.surface.deviation.range });
    layer.vertex_fields.forEach(function (field) {
      var key = field.kind === 'length' ? 'displacement' : field.kind === 'feature_map' ? 'features'
        : 'scalar:' + field.name;
      var legend = field.kind === 'length' ? 'displacement |p* \u2212 p| per vertex (' + field.unit + ')'
        : field.kind === 'feature_map'
          ? 'feature map v (\u2248 0 on sharp features; lines: v < ' + page.feature_threshold + ')'
          : field.name + ' (per vertex)';
      var title = field.kind === 'length' ? 'displacement |p* \u2212 p|'
        : field.kind === 'feature_map' ? 'feature map v' : field.name;
      modes.push({ key: key, title: title, kind: field.kind, field: field, legend: legend, range: field.range });
    });
    if (layer.surface.labels)
      modes.push({ key: 'labels', title: 'labels', kind: 'labels', perFace: true,
                   legend: 'labels (front: region behind the face; back: region in front)' });
    return modes;
  }

  // Fills `colours` (3 bytes per corner) for `surface`; the back of each face gets `back`
  // (labels only: the outside label).
  function fillColours(mode, view, colours, side) {
    var faces = view.faces, k = view.faceSize, faceCount = view.faceCount;
    var c, f, rgb;
    // A digital surface with other faces than its mesh has no per-face values: plain.
    var missing = mode.kind === 'labels' ? !view.data.labels : mode.perFace && !view.data[mode.field];
    if (mode.kind === 'plain' || missing) {
      rgb = plainColours[view.role];
      for (c = 0; c < colours.length; c += 3) { colours[c] = rgb[0]; colours[c + 1] = rgb[1]; colours[c + 2] = rgb[2]; }
      return;
    }
    if (mode.kind === 'labels') {
      var labels = buffer(view.data.labels.buffer), cache = {};
      for (f = 0; f < faceCount; ++f) {
        var label = labels[2 * f + side];
        rgb = cache[label] || (cache[label] = labelColour(label));
        for (c = 0; c < k; ++c) colours.set(rgb, 3 * (f * k + c));
      }
      return;
    }
    var table = tables[mode.kind], low = mode.range[0], scale = 255 / (mode.range[1] - mode.range[0]);
    var values = mode.perFace ? buffer(view.data[mode.field].buffer) : buffer(mode.field.buffer);
    for (f = 0; f < faceCount; ++f)
      for (c = 0; c < k; ++c) {
        var value = values[mode.perFace ? f : faces[f * k + c]], at = 3 * (f * k + c);
        if (value !== value) { colours.set(undefinedColour, at); continue; }  // NaN: no normal
        var i = Math.max(0, Math.min(255, Math.round((value - low) * scale)));
        colours[at] = table[3 * i]; colours[at + 1] = table[3 * i + 1]; colours[at + 2] = table[3 * i + 2];
      }
  }

  // ---- three.js objects of one surface ---------------------------------------------------------

  // The corners of every face get their own vertex, so that per-face colours stay per face.
  function SurfaceView(data, role) {
    this.data = data;
    this.role = role;
    this.positions = buffer(data.positions);
    this.faces = buffer(data.faces);
    this.faceSize = data.face_size;
    this.faceCount = data.face_count;
    var k = this.faceSize, corners = this.faceCount * k, p = this.positions, faces = this.faces;
    var cornerPositions = new Float32Array(corners * 3), normals = new Float32Array(corners * 3);
    var vertexNormals = role === 'surface' ? new Float32Array(p.length) : null;
    var index = new Uint32Array(this.faceCount * (k - 2) * 3), f, c, i, v;
    var n = [0, 0, 0];
    for (f = 0; f < this.faceCount; ++f) {
      var base = f * k;
      for (c = 0; c < k; ++c) {
        v = faces[base + c];
        cornerPositions[3 * (base + c)] = p[3 * v];
        cornerPositions[3 * (base + c) + 1] = p[3 * v + 1];
        cornerPositions[3 * (base + c) + 2] = p[3 * v + 2];
      }
      faceNormal(cornerPositions, base, k, n);
      if (vertexNormals)  // area-weighted: the cross product's length is twice the face's area
        for (c = 0; c < k; ++c) for (i = 0; i < 3; ++i) vertexNormals[3 * faces[base + c] + i] += n[i];
      else
        for (c = 0; c < k; ++c) normals.set(n, 3 * (base + c));
      triangles(cornerPositions, base, k, index, f * (k - 2) * 3);
    }
    if (vertexNormals)
      for (f = 0; f < corners; ++f) {
        v = faces[f];
        var x = vertexNormals[3 * v], y = vertexNormals[3 * v + 1], z = vertexNormals[3 * v + 2];
        var length = Math.sqrt(x * x + y * y + z * z) || 1;
        normals[3 * f] = x / length; normals[3 * f + 1] = y / length; normals[3 * f + 2] = z / length;
      }
    this.geometry = new THREE.BufferGeometry();
    this.geometry.setIndex(new THREE.BufferAttribute(index, 1));
    this.geometry.setAttribute('position', new THREE.BufferAttribute(cornerPositions, 3));
    this.geometry.setAttribute('normal', new THREE.BufferAttribute(normals, 3));
    this.colours = new THREE.BufferAttribute(new Uint8Array(corners * 3), 3, true);
    this.geometry.setAttribute('color', this.colours);
    this.geometry.computeBoundingSphere();
    this.bounds = new THREE.Box3().setFromBufferAttribute(this.geometry.attributes.position);
    this.front = new THREE.Mesh(this.geometry, surfaceMaterial(THREE.DoubleSide));
    this.group = new THREE.Group();
    this.group.add(this.front);
    this.back = null;      // labels: the back of the faces, with the outside labels
    this.wireframe = null;  // built when first shown
  }

  // Vector area normal of the face at corners [base, base + k) (not normalized).
  function faceNormal(p, base, k, n) {
    var a = 3 * base, b = a + 3, c = a + 6, d = k === 4 ? a + 9 : a;
    var ux = p[c] - p[a], uy = p[c + 1] - p[a + 1], uz = p[c + 2] - p[a + 2];
    var vx = k === 4 ? p[d] - p[b] : p[b] - p[a], vy = k === 4 ? p[d + 1] - p[b + 1] : p[b + 1] - p[a + 1];
    var vz = k === 4 ? p[d + 2] - p[b + 2] : p[b + 2] - p[a + 2];
    // quad: (c − a) × (d − b); triangle: (b − a) × (c − a) = −(c − a) × (b − a)
    var sign = k === 4 ? 1 : -1;
    n[0] = sign * (uy * vz - uz * vy); n[1] = sign * (uz * vx - ux * vz); n[2] = sign * (ux * vy - uy * vx);
  }

  // Triangles of the face at corners [base, base + k): a quad is split along its shorter diagonal.
  function triangles(p, base, k, index, at) {
    if (k === 3) { index[at] = base; index[at + 1] = base + 1; index[at + 2] = base + 2; return; }
    var d02 = 0, d13 = 0;
    for (var i = 0; i < 3; ++i) {
      var x = p[3 * (base + 2) + i] - p[3 * base + i], y = p[3 * (base + 3) + i] - p[3 * (base + 1) + i];
      d02 += x * x; d13 += y * y;
    }
    var t = d02 <= d13 ? [0, 1, 2, 0, 2, 3] : [0, 1, 3, 1, 2, 3];
    for (var j = 0; j < 6; ++j) index[at + j] = base + t[j];
  }

  function surfaceMaterial(side) {
    return new THREE.MeshPhongMaterial({
      vertexColors: THREE.VertexColors, side: side, shininess: 24, specular: 0x1c1c1c,
      // behind the lines drawn on the surface
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1
    });
  }

  SurfaceView.prototype.setMode = function (mode) {
    fillColours(mode, this, this.colours.array, 0);
    this.colours.needsUpdate = true;
    var labels = mode.kind === 'labels';
    this.front.material.side = labels ? THREE.FrontSide : THREE.DoubleSide;
    this.front.material.needsUpdate = true;
    if (labels && !this.back) {
      var geometry = new THREE.BufferGeometry();  // the same corners, other colours
      geometry.setIndex(this.geometry.index);
      geometry.setAttribute('position', this.geometry.attributes.position);
      geometry.setAttribute('normal', this.geometry.attributes.normal);
      geometry.setAttribute('color', new THREE.BufferAttribute(new Uint8Array(this.colours.array.length), 3, true));
      geometry.boundingSphere = this.geometry.boundingSphere;
      this.back = new THREE.Mesh(geometry, surfaceMaterial(THREE.BackSide));
      this.group.add(this.back);
    }
    if (this.back) {
      this.back.visible = labels;
      if (labels) {
        fillColours(mode, this, this.back.geometry.attributes.color.array, 1);
        this.back.geometry.attributes.color.needsUpdate = true;
      }
    }
  };

  SurfaceView.prototype.showWireframe = function (show) {
    if (show && !this.wireframe) {
      var k = this.faceSize, faces = this.faces, edges = new Uint32Array(this.faceCount * k * 2);
      for (var f = 0; f < this.faceCount; ++f)
        for (var c = 0; c < k; ++c) {
          edges[2 * (f * k + c)] = faces[f * k + c];
          edges[2 * (f * k + c) + 1] = faces[f * k + (c + 1) % k];
        }
      this.wireframe = lines(this.positions, edges, 0x1a2230, 0.55);
      this.group.add(this.wireframe);
    }
    if (this.wireframe) this.wireframe.visible = show;
  };

  function lines(positions, pairs, colour, opacity) {
    var geometry = new THREE.BufferGeometry();
    geometry.setIndex(new THREE.BufferAttribute(pairs, 1));
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    return new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({
      color: colour, transparent: opacity < 1, opacity: opacity }));
  }

  // ---- one layer: its surface, digital surface and feature lines --------------------------------

  function LayerView(layer, number) {
    this.layer = layer;
    this.number = number;
    this.modes = layerModes(layer);
    this.group = new THREE.Group();
    this.surface = null;
    this.digital = null;
    this.features = null;
    this.built = false;
  }

  LayerView.prototype.build = function () {
    if (this.built) return;
    this.surface = new SurfaceView(this.layer.surface, 'surface');
    this.group.add(this.surface.group);
    if (this.layer.digital) {
      this.digital = new SurfaceView(this.layer.digital, 'digital');
      this.group.add(this.digital.group);
    }
    if ('feature_edges' in this.layer) {
      this.features = lines(this.surface.positions, buffer(this.layer.feature_edges), 0x101010, 1);
      this.group.add(this.features);
    }
    this.built = true;
  };

  LayerView.prototype.mode = function (key) {
    for (var i = 0; i < this.modes.length; ++i) if (this.modes[i].key === key) return this.modes[i];
    return null;
  };

  LayerView.prototype.apply = function (state) {
    this.build();
    var mode = this.mode(state.colour) || this.modes[0];
    this.surface.group.visible = state.surface;
    this.surface.setMode(mode);
    this.surface.showWireframe(state.wireframe && state.surface);
    if (this.digital) {
      this.digital.group.visible = state.digital;
      this.digital.setMode(mode);
      this.digital.showWireframe(state.wireframe && state.digital);
    }
    if (this.features) this.features.visible = state.features && state.surface;
    return mode;
  };

  // ---- scene, camera, controls -------------------------------------------------------------------

  var canvasHolder = element('div', { id: 'dsreg-canvas' });
  document.body.appendChild(canvasHolder);
  var transparent = options.background === 'none';  // for pictures: the mesh alone
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, alpha: transparent });
  } catch (error) {
    window.dsregRecordError('This page needs WebGL, which this browser does not provide (' + error.message + ').');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x1d2127, transparent ? 0 : 1);
  if (transparent) root.classList.add('transparent');
  canvasHolder.appendChild(renderer.domElement);

  var scene = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x50505a, 0.45));
  var headlight = new THREE.DirectionalLight(0xffffff, 0.7);  // moves with the camera
  headlight.position.set(-0.4, 0.6, 1);
  headlight.target.position.set(0, 0, -1);
  camera.add(headlight);
  camera.add(headlight.target);

  var upAxes = { '+x': [1, 0, 0], '-x': [-1, 0, 0], '+y': [0, 1, 0], '-y': [0, -1, 0], '+z': [0, 0, 1], '-z': [0, 0, -1] };
  // The side the camera looks from at azimuth 0, for each up axis.
  var frontAxes = { '+x': [0, -1, 0], '-x': [0, 1, 0], '+y': [0, 0, 1], '-y': [0, 0, -1], '+z': [0, -1, 0], '-z': [0, 1, 0] };
  var up = (options.up || '+z').toLowerCase().replace(/^([xyz])$/, '+$1').replace(' ', '+');
  if (!(up in upAxes)) up = '+z';
  camera.up.fromArray(upAxes[up]);

  // OrbitControls turns about camera.up as it was when they were made: new ones for a new up.
  function makeControls() {
    var made = new THREE.OrbitControls(camera, renderer.domElement);
    made.screenSpacePanning = true;
    made.addEventListener('change', requestRender);
    return made;
  }
  var controls = makeControls();
  function setUp(axis) {
    up = axis;
    camera.up.fromArray(upAxes[up]);
    controls.dispose();
    controls = makeControls();
    resetView();
    requestRender();
  }

  var layers = page.layers.map(function (layer, i) { return new LayerView(layer, i + 1); });
  layers.forEach(function (view) { scene.add(view.group); view.group.visible = false; });

  var state = {
    layer: Math.max(1, Math.min(layers.length, Math.round(number('layer', 1)))),
    colour: options.colour || 'plain',
    surface: flag('surface', true),
    digital: flag('digital', false),
    wireframe: flag('wireframe', false),
    features: flag('features', true),
    panels: flag('panels', true)
  };

  // Camera looking at the centre of the current layer from (azimuth, elevation) degrees, at a
  // distance where its bounding sphere fills the view.
  function resetView() {
    var view = layers[state.layer - 1];
    view.build();
    var box = view.surface.bounds.clone();
    if (view.digital) box.union(view.digital.bounds);
    var sphere = box.getBoundingSphere(new THREE.Sphere());
    var radius = sphere.radius > 0 ? sphere.radius : 1;
    var azimuth = number('azimuth', 30) * Math.PI / 180, elevation = number('elevation', 20) * Math.PI / 180;
    var upVector = new THREE.Vector3().fromArray(upAxes[up]);
    var front = new THREE.Vector3().fromArray(frontAxes[up]);
    var side = new THREE.Vector3().crossVectors(upVector, front);
    var direction = front.multiplyScalar(Math.cos(azimuth) * Math.cos(elevation))
      .addScaledVector(side, Math.sin(azimuth) * Math.cos(elevation)).addScaledVector(upVector, Math.sin(elevation));
    var distance = radius / Math.sin(camera.fov * Math.PI / 360) * 0.95 / Math.min(1, camera.aspect);
    camera.near = radius / 200;
    camera.far = distance + 20 * radius;
    camera.position.copy(sphere.center).addScaledVector(direction, distance);
    controls.target.copy(sphere.center);
    camera.updateProjectionMatrix();
    controls.update();
  }

  function resize() {
    var width = window.innerWidth || 800, height = window.innerHeight || 600;
    renderer.setSize(width, height);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    requestRender();
  }

  var renderPending = false;
  function render() {
    renderPending = false;
    renderer.render(scene, camera);
  }
  function requestRender() {
    if (renderPending) return;
    renderPending = true;
    requestAnimationFrame(render);
  }

  // ---- panels: controls, legend, summary -------------------------------------------------------

  function element(tag, attributes, children) {
    var e = document.createElement(tag);
    Object.keys(attributes || {}).forEach(function (name) {
      if (name === 'text') e.textContent = attributes[name];
      else e.setAttribute(name, attributes[name]);
    });
    (children || []).forEach(function (child) { e.appendChild(child); });
    return e;
  }

  function checkbox(id, text, key) {
    var input = element('input', { type: 'checkbox', id: id });
    input.checked = state[key];
    input.addEventListener('change', function () { state[key] = input.checked; update(); });
    return element('label', { 'for': id, 'class': 'toggle' }, [input, document.createTextNode(' ' + text)]);
  }

  var panel = element('div', { id: 'dsreg-panel', 'class': 'dsreg-box' });
  panel.appendChild(element('h1', { text: page.title }));
  var layerList = element('div', { id: 'dsreg-layers' });
  layers.forEach(function (view) {
    var input = element('input', { type: 'radio', name: 'dsreg-layer', id: 'dsreg-layer-' + view.number });
    input.checked = view.number === state.layer;
    input.addEventListener('change', function () { selectLayer(view.number); });
    layerList.appendChild(element('label', { 'for': input.id, 'class': 'layer' },
      [input, document.createTextNode(' ' + view.number + '. ' + view.layer.name)]));
  });
  if (layers.length > 1) panel.appendChild(layerList);
  var colourSelect = element('select', { id: 'dsreg-colour' });
  colourSelect.addEventListener('change', function () { state.colour = colourSelect.value; update(); });
  panel.appendChild(element('label', { 'for': 'dsreg-colour', 'class': 'row' },
    [document.createTextNode('colour '), colourSelect]));
  var upSelect = element('select', { id: 'dsreg-up' });
  Object.keys(upAxes).forEach(function (axis) {
    var option = element('option', { value: axis, text: axis });
    option.selected = axis === up;
    upSelect.appendChild(option);
  });
  upSelect.addEventListener('change', function () { setUp(upSelect.value); });
  panel.appendChild(element('label', { 'for': 'dsreg-up', 'class': 'row' }, [document.createTextNode('up '), upSelect]));
  var toggles = {
    surface: checkbox('dsreg-show-surface', 'surface', 'surface'),
    digital: checkbox('dsreg-show-digital', 'digital surface', 'digital'),
    wireframe: checkbox('dsreg-show-wireframe', 'wireframe', 'wireframe'),
    features: checkbox('dsreg-show-features', 'feature lines', 'features')
  };
  Object.keys(toggles).forEach(function (key) { panel.appendChild(toggles[key]); });
  var resetButton = element('button', { type: 'button', id: 'dsreg-reset', text: 'reset view' });
  resetButton.addEventListener('click', function () { resetView(); requestRender(); });
  panel.appendChild(resetButton);
  panel.appendChild(element('p', { 'class': 'help', text: 'drag: turn \u00b7 right or shift drag: pan \u00b7 ' +
    'wheel: zoom \u00b7 R: reset \u00b7 W: wireframe \u00b7 D: digital surface' +
    (layers.length > 1 ? ' \u00b7 1\u20139: layer' : '') }));

  var legend = element('div', { id: 'dsreg-legend', 'class': 'dsreg-box' });
  var summary = element('div', { id: 'dsreg-summary', 'class': 'dsreg-box' });
  [panel, legend, summary].forEach(function (box) {
    if (!state.panels) box.hidden = true;
    document.body.appendChild(box);
  });

  function formatNumber(x) {
    if (x === 0) return '0';
    var text = Math.abs(x) >= 1e4 || Math.abs(x) < 1e-3 ? x.toExponential(2) : x.toPrecision(3);
    return text.indexOf('e') < 0 && text.indexOf('.') >= 0 ? text.replace(/\.?0+$/, '') : text;
  }

  function showLegend(view, mode) {
    legend.textContent = '';
    if (mode.kind === 'plain' || mode.kind === 'labels') {
      var entries = mode.kind === 'plain'
        ? [['surface', plainColours.surface]].concat(view.digital ? [['digital surface', plainColours.digital]] : [])
        : view.layer.surface.labels.values.slice(0, 40).map(function (label) { return ['label ' + label, labelColour(label)]; });
      legend.appendChild(element('div', { 'class': 'title', text: mode.kind === 'plain' ? 'colours' : mode.legend }));
      entries.forEach(function (entry) {
        var swatch = element('span', { 'class': 'swatch' });
        swatch.style.background = cssColour(entry[1]);
        legend.appendChild(element('div', { 'class': 'entry' }, [swatch, document.createTextNode(' ' + entry[0])]));
      });
      if (mode.kind === 'labels' && view.layer.surface.labels.values.length > 40)
        legend.appendChild(element('div', { 'class': 'entry', text: '\u2026 ' +
          (view.layer.surface.labels.values.length - 40) + ' more labels' }));
      return;
    }
    legend.appendChild(element('div', { 'class': 'title', text: mode.legend }));
    var bar = element('canvas', { width: 240, height: 14, 'class': 'bar' });
    var context = bar.getContext('2d'), table = tables[mode.kind];
    for (var x = 0; x < 240; ++x) {
      var i = Math.round(x * 255 / 239);
      context.fillStyle = cssColour([table[3 * i], table[3 * i + 1], table[3 * i + 2]]);
      context.fillRect(x, 0, 1, 14);
    }
    legend.appendChild(bar);
    var low = mode.range[0], high = mode.range[1];
    // Values beyond the range take the end colours: above the 99th percentile for angles and
    // lengths, outside [0, 1] for the feature map (other ranges are the values' minimum and maximum).
    var clippedLow = mode.kind === 'feature_map', clippedHigh = mode.kind !== 'scalar';
    var ticks = element('div', { 'class': 'ticks' }, [low, (low + high) / 2, high].map(function (value, i) {
      var prefix = i === 0 && clippedLow ? '\u2264 ' : i === 2 && clippedHigh ? '\u2265 ' : '';
      return element('span', { text: prefix + formatNumber(value) });
    }));
    legend.appendChild(ticks);
    if (mode.kind === 'angle') {
      var swatch = element('span', { 'class': 'swatch' });
      swatch.style.background = cssColour(undefinedColour);
      legend.appendChild(element('div', { 'class': 'entry' }, [swatch, document.createTextNode(' face without normal')]));
    }
  }

  function summaryTable(lines) {
    return element('table', {}, lines.map(function (line) {
      return element('tr', {}, [element('th', { text: line[0] }), element('td', { text: line[1] })]);
    }));
  }

  function showSummary(view) {
    summary.textContent = '';
    var details = element('details', { open: '' }, [element('summary', { text: 'summary' })]);
    if (page.summary.length) details.appendChild(summaryTable(page.summary));
    var counts = [['vertices', String(view.layer.surface.vertex_count)],
                  ['faces', view.layer.surface.face_count + (view.layer.surface.face_size === 4 ? ' quads' : ' triangles')]];
    details.appendChild(element('h2', { text: view.layer.name }));
    details.appendChild(summaryTable(counts.concat(view.layer.summary)));
    summary.appendChild(details);
  }

  // ---- state changes ---------------------------------------------------------------------------

  function update() {
    var view = layers[state.layer - 1];
    layers.forEach(function (other) { other.group.visible = other === view; });
    var mode = view.apply(state);  // state.colour stays as asked, for layers that have it
    colourSelect.textContent = '';
    view.modes.forEach(function (m) {
      var option = element('option', { value: m.key, text: m.title });
      option.selected = m === mode;
      colourSelect.appendChild(option);
    });
    toggles.digital.hidden = !view.digital;
    toggles.features.hidden = !view.features;
    Object.keys(toggles).forEach(function (key) { toggles[key].querySelector('input').checked = state[key]; });
    showLegend(view, mode);
    showSummary(view);
    root.setAttribute('data-layer', String(state.layer));
    root.setAttribute('data-colour', mode.key);
    requestRender();
  }

  function selectLayer(number) {
    if (number < 1 || number > layers.length) return;
    state.layer = number;
    var radio = document.getElementById('dsreg-layer-' + number);
    if (radio) radio.checked = true;
    update();
  }

  window.addEventListener('keydown', function (event) {
    if (event.target && (event.target.tagName === 'INPUT' || event.target.tagName === 'SELECT')) return;
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    var key = event.key;
    if (key === 'r' || key === 'R') { resetView(); requestRender(); }
    else if (key === 'w' || key === 'W') { state.wireframe = !state.wireframe; update(); }
    else if (key === 'd' || key === 'D') { state.digital = !state.digital; update(); }
    else if (/^[1-9]$/.test(key)) selectLayer(Number(key));
  });
  window.addEventListener('resize', resize);

  document.title = page.title;
  resize();
  update();
  resetView();
  render();  // now, so that a screenshot taken when the page has loaded shows it
  root.setAttribute('data-load-seconds', (performance.now() / 1000).toFixed(2));  // since navigation began
  if (root.getAttribute('data-status') !== 'error') root.setAttribute('data-status', 'ready');
})();
