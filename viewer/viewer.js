// The viewer page's script: builds the three.js scene from the data lazyboe-view inlined
// (lib/view/view_data.h describes it), poses the robot by forward kinematics from the URDF's
// joint origins and axes (as lib/robot/kinematics.cpp does, in double precision), and plays the
// trajectories. Everything the tests read is on document.body's data-* attributes and in
// window.lazyboeView.
(function () {
  'use strict';
  const data = JSON.parse(document.getElementById('lazyboe-data').textContent);
  const body = document.body;
  const $ = (id) => document.getElementById(id);
  const messages = [];
  function say(text) {
    messages.push(text);
    const li = document.createElement('li');
    li.textContent = text;
    $('messages').appendChild(li);
  }

  // ---- Kinematics: poses {R: 3x3 row-major, p: [x, y, z]} -------------------------------
  function mul3(A, B) {
    const C = new Array(9);
    for (let r = 0; r < 3; ++r)
      for (let c = 0; c < 3; ++c)
        C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
    return C;
  }
  function apply3(A, v) {
    return [A[0] * v[0] + A[1] * v[1] + A[2] * v[2], A[3] * v[0] + A[4] * v[1] + A[5] * v[2],
            A[6] * v[0] + A[7] * v[1] + A[8] * v[2]];
  }
  function compose(a, b) {
    const p = apply3(a.R, b.p);
    return {R: mul3(a.R, b.R), p: [p[0] + a.p[0], p[1] + a.p[1], p[2] + a.p[2]]};
  }
  function axisAngle(u, angle) {  // Rodrigues' formula, u a unit vector
    const c = Math.cos(angle), s = Math.sin(angle), t = 1 - c;
    return [t * u[0] * u[0] + c, t * u[0] * u[1] - s * u[2], t * u[0] * u[2] + s * u[1],
            t * u[0] * u[1] + s * u[2], t * u[1] * u[1] + c, t * u[1] * u[2] - s * u[0],
            t * u[0] * u[2] - s * u[1], t * u[1] * u[2] + s * u[0], t * u[2] * u[2] + c];
  }
  // Pose of every link in the base frame at joint positions q.
  function linkPoses(robot, q) {
    const bodies = [];
    robot.joints.forEach((j, i) => {
      const X = j.type === 'revolute'
        ? {R: mul3(j.origin.R, axisAngle(j.axis, q[i])), p: j.origin.p}
        : compose(j.origin, {R: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: j.axis.map((a) => a * q[i])});
      bodies.push(i === 0 ? X : compose(bodies[i - 1], X));
    });
    return robot.links.map((l) => (l.body < 0 ? l.in_body : compose(bodies[l.body], l.in_body)));
  }
  // [w, x, y, z] with w >= 0, as lazyboe-robot fk prints it.
  function quaternion(R) {
    const m = new THREE.Matrix4().set(R[0], R[1], R[2], 0, R[3], R[4], R[5], 0, R[6], R[7], R[8], 0, 0, 0, 0, 1);
    const q = new THREE.Quaternion().setFromRotationMatrix(m).normalize();
    const s = q.w < 0 ? -1 : 1;
    return [s * q.w, s * q.x, s * q.y, s * q.z];
  }

  // ---- Scene ----------------------------------------------------------------------------
  // three.js layer of what moves during playback (the played robot); everything else is on
  // layer 0 and is still between user actions. The translucent still objects are also on the
  // overlay layer (section "Still layers").
  const MOVING_LAYER = 1, OVERLAY_LAYER = 2;
  // A software rasteriser (SwiftShader in headless Chromium, llvmpipe) draws without
  // antialiasing: multisampling on the CPU costs most of the frame.
  function webglRenderer() {
    const gl = document.createElement('canvas').getContext('webgl');
    if (!gl) return null;
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    return String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  }
  const rendererName = webglRenderer();
  if (rendererName === null) {
    body.setAttribute('data-status', 'no-webgl');
    throw new Error('this browser has no WebGL: the 3-D scene cannot be drawn');
  }
  const software = /swiftshader|llvmpipe|software/i.test(rendererName);
  const view = $('view');
  const renderer = new THREE.WebGLRenderer({antialias: !software});
  // Options in the page's URL (view.html?scale=0.5&cache=0): `scale`, pixels drawn per CSS
  // pixel (0.25 to 1; default 1); `cache`, whether the still layers are drawn once and reused
  // (section "Still layers" below; default: on for a software renderer, off with a GPU).
  const options = new URLSearchParams(window.location.search);
  const scaleOption = Number(options.get('scale'));
  const renderScale = scaleOption >= 0.25 && scaleOption <= 1 ? scaleOption : 1;
  renderer.setPixelRatio((window.devicePixelRatio || 1) * renderScale);
  view.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f3f5);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 50);
  camera.up.set(0, 0, 1);  // the robot's base frame is z-up
  camera.position.set(1.9, -1.5, 1.25);
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.set(0.35, 0, 0.35);
  controls.update();
  const sky = new THREE.HemisphereLight(0xffffff, 0x8890a0, 0.75);
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.set(2, -1, 3);
  for (const light of [sky, sun]) {
    light.layers.enable(MOVING_LAYER);  // lights every layer
    light.layers.enable(OVERLAY_LAYER);
    scene.add(light);
  }
  const grid = new THREE.GridHelper(2, 20, 0xb0b4bc, 0xd4d7dc);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);

  function resize() {
    const w = view.clientWidth, h = view.clientHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
    stillLayers.resize();
  }
  const stillLayers = makeStillLayers();
  controls.addEventListener('change', stillLayers.changed);
  window.addEventListener('resize', resize);
  resize();

  function setMatrix(object, pose) {
    const R = pose.R, p = pose.p;
    object.matrixAutoUpdate = false;
    object.matrix.set(R[0], R[1], R[2], p[0], R[3], R[4], R[5], p[1], R[6], R[7], R[8], p[2], 0, 0, 0, 1);
    object.matrixWorldNeedsUpdate = true;
  }
  // ---- Still layers ---------------------------------------------------------------------
  // A software rasteriser spends most of a frame drawing the bundle's points, the paths and the
  // obstacles again although only the played robot moves. With the cache, layer 0 is drawn
  // into a colour and depth texture when something on it changes (the camera, a selection, the
  // colouring, the window's size); each frame copies both back (one full-screen triangle pair
  // writing colour and depth) and draws the moving layer over them, depth-tested, so the robot
  // still passes behind obstacles. The robot marks its pixels in the stencil buffer, and the
  // translucent still objects (ghosts, faint paths, the goal region) are drawn again on those
  // pixels only: where one is in front of the robot it is blended over it, as without the cache,
  // and nowhere is it blended twice.
  function makeStillLayers() {
    const wanted = options.has('cache') ? options.get('cache') !== '0' : software;
    const canCache = renderer.extensions.get('WEBGL_depth_texture') && renderer.extensions.get('EXT_frag_depth');
    if (!wanted || !canCache) {
      camera.layers.enable(MOVING_LAYER);
      return {cached: false, changed() {}, resize() {}, render() { renderer.render(scene, camera); }};
    }
    const target = new THREE.WebGLRenderTarget(1, 1, {minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
                                                      depthBuffer: true, stencilBuffer: false});
    target.depthTexture = new THREE.DepthTexture();
    target.depthTexture.type = THREE.UnsignedIntType;
    const copy = new THREE.Mesh(new THREE.PlaneBufferGeometry(2, 2), new THREE.ShaderMaterial({
      uniforms: {colour: {value: target.texture}, depth: {value: target.depthTexture}},
      vertexShader: 'varying vec2 uv0; void main() { uv0 = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }',
      fragmentShader: 'uniform sampler2D colour; uniform sampler2D depth; varying vec2 uv0;\n' +
        'void main() { gl_FragColor = texture2D(colour, uv0); gl_FragDepthEXT = texture2D(depth, uv0).x; }',
      extensions: {fragDepth: true}, depthTest: true, depthFunc: THREE.AlwaysDepth, depthWrite: true}));
    copy.frustumCulled = false;
    const copyScene = new THREE.Scene();
    copyScene.add(copy);
    const copyCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    let dirty = true, prepared = false;
    function prepare() {  // the scene is complete at the first frame
      scene.traverse((o) => {
        if (!o.material) return;
        if (o.layers.test(camera.layers) && o.material.transparent) {
          o.layers.enable(OVERLAY_LAYER);
          Object.assign(o.material, {stencilWrite: true, stencilFunc: THREE.EqualStencilFunc, stencilRef: 1,
                                     stencilZPass: THREE.KeepStencilOp});
        } else if ((o.layers.mask & (1 << MOVING_LAYER)) !== 0) {
          Object.assign(o.material, {stencilWrite: true, stencilFunc: THREE.AlwaysStencilFunc, stencilRef: 1,
                                     stencilZPass: THREE.ReplaceStencilOp});
        }
      });
      prepared = true;
    }
    return {
      cached: true,
      changed() { dirty = true; },
      resize() {
        const size = renderer.getDrawingBufferSize(new THREE.Vector2());
        target.setSize(size.x, size.y);
        dirty = true;
      },
      render() {
        camera.layers.set(0);
        if (!prepared) prepare();
        if (dirty) {
          renderer.setRenderTarget(target);
          renderer.render(scene, camera);
          renderer.setRenderTarget(null);
          dirty = false;
        }
        renderer.render(copyScene, copyCamera);
        // Over the copy: no clearing, not even by the scene's background colour.
        const background = scene.background;
        scene.background = null;
        renderer.autoClear = false;
        camera.layers.set(MOVING_LAYER);
        renderer.render(scene, camera);
        camera.layers.set(OVERLAY_LAYER);
        renderer.render(scene, camera);
        renderer.autoClear = true;
        scene.background = background;
      },
    };
  }

  // A shape of lib/robot/robot_model.h; cylinders and capsules along their local z.
  function shapeObject(s, material) {
    const along = (g) => g.rotateX(Math.PI / 2);
    switch (s.type) {
      case 'sphere': return new THREE.Mesh(new THREE.SphereBufferGeometry(s.radius, 20, 12), material);
      case 'box': return new THREE.Mesh(new THREE.BoxBufferGeometry(s.size[0], s.size[1], s.size[2]), material);
      case 'cylinder':
        return new THREE.Mesh(along(new THREE.CylinderBufferGeometry(s.radius, s.radius, s.length, 24)), material);
      case 'capsule': {  // one geometry (a cylinder and two spheres): one draw call
        const g = along(new THREE.CylinderGeometry(s.radius, s.radius, s.length, 20, 1, true));
        for (const z of [-s.length / 2, s.length / 2])
          g.merge(new THREE.SphereGeometry(s.radius, 20, 10).translate(0, 0, z));
        return new THREE.Mesh(new THREE.BufferGeometry().fromGeometry(g), material);
      }
      case 'mesh': {  // an obstacle given as a triangle mesh
        const g = new THREE.BufferGeometry();
        g.setAttribute('position', new THREE.Float32BufferAttribute(s.vertices, 3));
        g.setIndex(s.triangles);
        g.computeVertexNormals();
        return new THREE.Mesh(g, material);
      }
      case 'cells': return cellsObject(s, material);
      default: throw new Error('unknown shape type ' + s.type + ' (' + s.name + ')');
    }
  }

  // The occupied cells of an octree obstacle (a voxelised point cloud, an OctoMap): boxes merged
  // into one geometry, or points (one per cell) when there are too many boxes to draw smoothly.
  function cellsObject(s, material) {
    const n = s.sizes.length;
    if (n > 20000) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.Float32BufferAttribute(s.centres, 3));
      return new THREE.Points(g, new THREE.PointsMaterial({color: material.color, size: s.sizes[0]}));
    }
    const g = new THREE.Geometry();
    for (let k = 0; k < n; ++k) {
      const c = s.centres.slice(3 * k, 3 * k + 3);
      g.merge(new THREE.BoxGeometry(s.sizes[k], s.sizes[k], s.sizes[k]).translate(c[0], c[1], c[2]));
    }
    return new THREE.Mesh(new THREE.BufferGeometry().fromGeometry(g), material);
  }

  const robot = data.robot;
  const robotLayer = new THREE.Group();  // the robot and its ghosts
  scene.add(robotLayer);
  const visuals = robot.visuals || [];
  const visualLinks = new Set(visuals.map((v) => v.link));
  const drawnShapes = visuals.concat(robot.shapes.filter((s) => !visualLinks.has(s.link)));
  function makeRobot(colour, opacity, layer) {
    // A ghost's surfaces are pushed back in depth, so where it coincides with the robot (at the
    // start, at the goal) the robot is drawn, not a flicker of both.
    const ghost = opacity < 1;
    const material = new THREE.MeshLambertMaterial({color: colour, transparent: ghost, opacity: opacity,
                                                    depthWrite: !ghost, polygonOffset: ghost,
                                                    polygonOffsetFactor: 2, polygonOffsetUnits: 2});
    const group = new THREE.Group();
    // A link with URDF <visual> elements is drawn from them; another link from its collision
    // geometry: a mesh as that mesh (`display`), whatever stands for it in the checks (a
    // fitted capsule, a convex hull), other shapes as they are.
    const parts = drawnShapes.map((s) => {
      const shown = s.display ? Object.assign({type: 'mesh', name: s.name}, s.display) : s;
      const o = shapeObject(shown, material);
      o.layers.set(layer);
      group.add(o);
      return {object: o, pose: shown.pose};
    });
    robotLayer.add(group);
    let payload = null;  // {box: the mesh, link, at: its pose on the link}
    let lastQ = null;
    return {
      group: group,
      setQ(q) {
        if (layer !== MOVING_LAYER) stillLayers.changed();
        lastQ = q;
        const poses = linkPoses(robot, q);
        drawnShapes.forEach((s, i) => setMatrix(parts[i].object, compose(poses[s.link], parts[i].pose)));
        if (payload) setMatrix(payload.box, compose(poses[payload.link], payload.at));
      },
      // The query's payload as a box at its centre of mass on its link (default the tip), or
      // none (p null).
      setPayload(p) {
        if (payload) { group.remove(payload.box); payload.box.geometry.dispose(); payload = null; }
        if (!p) return;
        const link = p.link === undefined ? robot.tip : robot.links.findIndex((l) => l.name === p.link);
        if (link < 0) { say('payload.link: unknown link ' + p.link + ': the payload is not drawn'); return; }
        const box = new THREE.Mesh(new THREE.BoxBufferGeometry(p.box[0], p.box[1], p.box[2]), payloadMaterial);
        box.layers.set(layer);
        group.add(box);
        payload = {box: box, link: link, at: {R: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: p.com}};
        if (lastQ) this.setQ(lastQ);
      },
      payloadPosition() { return payload ? payload.box.matrix.elements.slice(12, 15) : null; },
    };
  }
  const payloadMaterial = new THREE.MeshLambertMaterial({color: 0x8a6d3b});
  const mainRobot = makeRobot(0xe09040, 1, MOVING_LAYER);
  const startGhost = makeRobot(0x30a050, 0.3, 0);
  const goalGhosts = [makeRobot(0xc03030, 0.3, 0)];  // more are made when a goal set needs them
  const goalMarks = new THREE.Group();  // tolerance spheres and pose axes, remade per selection
  scene.add(goalMarks);
  const goalSphere = new THREE.SphereBufferGeometry(1, 24, 16);
  const goalMaterial = new THREE.MeshLambertMaterial({color: 0xc03030, transparent: true, opacity: 0.3});

  const obstacleMaterial = new THREE.MeshLambertMaterial({color: 0x7088a8});
  for (const o of data.environment.obstacles) {
    const object = shapeObject(o, obstacleMaterial);
    setMatrix(object, o.pose);
    scene.add(object);
  }
  const zero = robot.joints.map(() => 0);
  mainRobot.setQ(zero);
  if (drawnShapes.length === 0) say('The robot has no geometry to draw (no visual or collision elements).');

  // ---- Trajectories and failed queries --------------------------------------------------
  const results = data.results;
  const trajectories = results ? results.trajectories : [];
  const failures = results ? results.failures : [];
  const plural = (n, one, many) => n + ' ' + (n === 1 ? one : many || one + 's');
  const tipPosition = (q) => linkPoses(robot, q)[robot.tip].p;
  // Every end-effector path in one draw call (segments coloured per trajectory, faint), and
  // the selected one drawn again on top, opaque.
  const segments = [], segmentColours = [];
  trajectories.forEach((tr, i) => {
    tr.colour = new THREE.Color().setHSL((i * 0.618034) % 1, 0.75, 0.45);
    tr.pathPoints = new Float32Array(tr.samples.q.length * 3);
    tr.samples.q.forEach((q, k) => tr.pathPoints.set(tipPosition(q), 3 * k));
    for (let k = 3; k < tr.pathPoints.length; k += 3) {
      segments.push(...tr.pathPoints.subarray(k - 3, k + 3));
      segmentColours.push(tr.colour.r, tr.colour.g, tr.colour.b, tr.colour.r, tr.colour.g, tr.colour.b);
    }
  });
  const allPaths = new THREE.BufferGeometry();
  allPaths.addAttribute('position', new THREE.BufferAttribute(new Float32Array(segments), 3));
  allPaths.addAttribute('color', new THREE.BufferAttribute(new Float32Array(segmentColours), 3));
  scene.add(new THREE.LineSegments(allPaths, new THREE.LineBasicMaterial({
    vertexColors: THREE.VertexColors, transparent: true, opacity: 0.6, depthWrite: false})));
  // The selected path is drawn last and over everything (no depth test): never hidden by the
  // bundle's points or an obstacle. (WebGL draws lines one pixel wide whatever linewidth says.)
  const selectedPath = new THREE.Line(new THREE.BufferGeometry(),
                                      new THREE.LineBasicMaterial({depthTest: false}));
  selectedPath.renderOrder = 10;
  selectedPath.visible = false;
  scene.add(selectedPath);
  if (!results) say('No results file given (lazyboe-view --results): robot and obstacles only.');
  else if (trajectories.length === 0)
    say('No trajectories: ' + plural(results.results, 'result') + ' in ' + results.path + ', none with a trajectory to play.');
  if (results && results.without_trajectory.length > 0)
    say(results.without_trajectory.length + ' successful results carry no trajectory ' +
        '(run lazyboe-query with --trajectories inline or csv).');
  if (failures.length > 0) say(failures.length + ' of ' + plural(results.results, 'query', 'queries') + ' failed (listed below).');

  const fmt = (v, unit) => (v === undefined || v === null ? '-' : Number(v).toFixed(2) + unit);
  function row(cells, onClick) {
    const tr = document.createElement('tr');
    for (const c of cells) {
      const td = document.createElement('td');
      if (c instanceof Node) td.appendChild(c); else td.textContent = c;
      tr.appendChild(td);
    }
    tr.addEventListener('click', onClick);
    return tr;
  }
  trajectories.forEach((tr, i) => {
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = '#' + tr.colour.getHexString();
    tr.row = row([swatch, tr.id, tr.planner, fmt(tr.cost, ''), fmt(tr.duration, ' s'), String(tr.edges.length)],
                 () => select('trajectory', i));
    tr.row.title = 'line ' + tr.line + ', success, time to first solution ' + fmt(tr.time_to_first_solution, ' s') +
                   ', edges: ' + (tr.edges.join(' ') || 'none');
    $('trajectories').tBodies[0].appendChild(tr.row);
  });
  failures.forEach((f, i) => {
    f.row = row([f.id === null ? '(no id)' : f.id, f.planner || '-', f.reason], () => select('failure', i));
    f.row.cells[2].className = 'reason';
    f.row.title = 'line ' + f.line + (f.start ? '' : ': start and goal unknown (pass lazyboe-view --queries)');
    $('failures').tBodies[0].appendChild(f.row);
  });
  $('trajectory-count').textContent = '(' + trajectories.length + ')';
  $('failure-count').textContent = '(' + failures.length + ')';
  $('failure-section').hidden = failures.length === 0;

  // A query's goal: a ghost per joint goal, a sphere of the position tolerance per position or
  // pose goal, and per pose goal its frame as axes (x red, y green, z blue, 10 cm); every
  // member of a goal set.
  function showGoal(goal) {
    for (const o of goalMarks.children.slice()) {
      goalMarks.remove(o);
      if (o instanceof THREE.AxesHelper) {
        o.geometry.dispose();
        o.material.dispose();
      }
    }
    goalGhosts.forEach((g) => { g.group.visible = false; });
    let ghosts = 0;
    for (const g of !goal ? [] : goal.set || [goal]) {
      if (g.q) {
        if (ghosts === goalGhosts.length) goalGhosts.push(makeRobot(0xc03030, 0.3, 0));
        goalGhosts[ghosts].group.visible = true;
        goalGhosts[ghosts++].setQ(g.q);
      }
      const p = g.pose ? g.pose.p : g.position;
      if (p) {
        const sphere = new THREE.Mesh(goalSphere, goalMaterial);
        sphere.position.set(p[0], p[1], p[2]);
        sphere.scale.setScalar(g.tolerance || (g.pose ? 0.01 : 0.02));
        goalMarks.add(sphere);
      }
      if (g.pose) {
        const axes = new THREE.AxesHelper(0.1);
        setMatrix(axes, g.pose);
        goalMarks.add(axes);
      }
    }
  }
  // Ghosts at a query's start and goal, and its payload on the robot and the start ghost.
  function showEnds(start, goal, payload) {
    startGhost.group.visible = !!start;
    for (const r of [mainRobot, startGhost]) r.setPayload(payload || null);
    if (start) startGhost.setQ(start);
    showGoal(goal);
  }
  // What showGoal and setPayload drew for the selection (the tests read it).
  function goalView() {
    const count = (type) => goalMarks.children.filter((o) => o instanceof type).length;
    return {ghosts: goalGhosts.filter((g) => g.group.visible).length, spheres: count(THREE.Mesh),
            axes: count(THREE.AxesHelper), payload: mainRobot.payloadPosition()};
  }

  // ---- Playback -------------------------------------------------------------------------
  const play = {selected: null, time: 0, playing: false, speed: 1};
  function selectedSamples() { return play.selected ? play.selected.samples : null; }
  function qAt(samples, t) {  // linear interpolation between the samples around t
    const ts = samples.t;
    if (t <= ts[0]) return samples.q[0];
    if (t >= ts[ts.length - 1]) return samples.q[ts.length - 1];
    let lo = 0, hi = ts.length - 1;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
    const a = (t - ts[lo]) / Math.max(1e-12, ts[hi] - ts[lo]);
    return samples.q[lo].map((v, k) => v + a * (samples.q[hi][k] - v));
  }
  function duration() { const s = selectedSamples(); return s ? s.t[s.t.length - 1] : 0; }
  // The time label and slider follow playback at 10 Hz: changed every frame, they would have
  // the browser lay out and repaint the panel every frame too.
  let lastLabel = -Infinity;
  function setTime(t, playing) {
    play.time = Math.max(0, Math.min(duration(), t));
    const s = selectedSamples();
    if (s) mainRobot.setQ(qAt(s, play.time));
    const now = performance.now();
    if (playing && now - lastLabel < 100) return;
    lastLabel = now;
    $('time').textContent = play.time.toFixed(2) + ' / ' + duration().toFixed(2) + ' s';
    $('timeline').value = duration() > 0 ? String(Math.round(1000 * play.time / duration())) : '0';
  }
  function select(kind, i) {
    stillLayers.changed();
    for (const x of trajectories.concat(failures)) x.row.classList.remove('selected');
    if (kind === 'trajectory') {
      const tr = trajectories[i];
      play.selected = tr;
      tr.row.classList.add('selected');
      const q = tr.samples.q;
      showEnds(tr.start || q[0], tr.goal || {q: q[q.length - 1]}, tr.payload);
      mainRobot.group.visible = true;
      selectedPath.geometry.dispose();
      selectedPath.geometry = new THREE.BufferGeometry();
      selectedPath.geometry.addAttribute('position', new THREE.BufferAttribute(tr.pathPoints, 3));
      selectedPath.material.color = tr.colour;
      selectedPath.visible = true;
      $('selected-info').textContent = tr.id + ' (' + tr.planner + ', line ' + tr.line + '): success, cost ' +
        fmt(tr.cost, '') + ', duration ' + fmt(tr.duration, ' s') + ', first solution after ' +
        fmt(tr.time_to_first_solution, ' s') + '; edges ' + (tr.edges.join(' ') || 'none') +
        ' (-1: a command that is not a bundle edge)';
      setTime(0);
    } else {
      const f = failures[i];
      play.selected = null;
      play.playing = false;
      selectedPath.visible = false;
      f.row.classList.add('selected');
      showEnds(f.start, f.goal, f.payload);
      mainRobot.group.visible = !f.start;  // the start ghost stands for the robot
      $('selected-info').textContent = (f.id === null ? '(no id)' : f.id) + ' (' + (f.planner || '-') + ', line ' +
        f.line + '): ' + f.kind + ': ' + f.reason;
      $('time').textContent = 'failed: ' + f.reason + (f.start ? ' (start: green, goal: red)' : ' (start and goal unknown: lazyboe-view --queries)');
    }
    $('play').textContent = play.playing ? 'Pause' : 'Play';
  }
  $('play').addEventListener('click', () => {
    if (!play.selected) return;
    if (!play.playing && play.time >= duration()) setTime(0);
    play.playing = !play.playing;
    $('play').textContent = play.playing ? 'Pause' : 'Play';
  });
  $('timeline').addEventListener('input', (e) => { setTime(duration() * Number(e.target.value) / 1000); });
  $('speed').addEventListener('change', (e) => { play.speed = Number(e.target.value); });
  showEnds(null, null);
  if (trajectories.length > 0) select('trajectory', 0);
  else if (failures.length > 0) select('failure', 0);

  // ---- Bundle sample --------------------------------------------------------------------
  const bundle = data.bundle;
  let bundlePoints = null;
  // Colour ramps from "thin" (red) to "well covered" (green); P_collision is reversed.
  const ramps = {
    p_lazy_prop: {label: 'P_lazy_prop', low: 0, high: 1, reversed: false},
    p_collision: {label: 'P_collision', low: 0, high: 1, reversed: true},
    density: {label: 'neighbours within theta', low: 0, high: null, reversed: false},
  };
  function colourBundle(field) {
    stillLayers.changed();
    const values = bundle[field], ramp = ramps[field];
    const high = ramp.high === null ? Math.max(1, ...values) : ramp.high;
    const colours = bundlePoints.geometry.attributes.color;
    const c = new THREE.Color();
    values.forEach((v, i) => {
      let x = Math.min(1, Math.max(0, (v - ramp.low) / (high - ramp.low)));
      if (ramp.reversed) x = 1 - x;
      c.setHSL(x / 3, 0.85, 0.45);  // hue 0 (red) to 1/3 (green)
      colours.setXYZ(i, c.r, c.g, c.b);
    });
    colours.needsUpdate = true;
    $('legend-low').textContent = String(ramp.reversed ? high : ramp.low);
    $('legend-high').textContent = String(ramp.reversed ? ramp.low : high);
    $('legend-bar').style.background = 'linear-gradient(to right, hsl(0,85%,45%), hsl(60,85%,45%), hsl(120,85%,45%))';
  }
  if (bundle) {
    const n = bundle.points.length / 3;
    const g = new THREE.BufferGeometry();
    g.addAttribute('position', new THREE.BufferAttribute(new Float32Array(bundle.points), 3));
    g.addAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
    bundlePoints = new THREE.Points(g, new THREE.PointsMaterial({size: 3, sizeAttenuation: false,
                                                                 vertexColors: THREE.VertexColors}));
    scene.add(bundlePoints);
    // Shown by default only when there is no trajectory to look at: thousands of points would
    // cover the planned paths.
    bundlePoints.visible = trajectories.length === 0;
    $('show-bundle').checked = bundlePoints.visible;
    $('show-bundle').addEventListener('change', (e) => {
      bundlePoints.visible = e.target.checked;
      stillLayers.changed();
    });
    const fields = Object.keys(ramps).filter((f) => Array.isArray(bundle[f]));
    for (const f of fields) {
      const o = document.createElement('option');
      o.value = f;
      o.textContent = ramps[f].label;
      $('colour-by').appendChild(o);
    }
    const initial = fields.includes(data.colour_by) ? data.colour_by : 'density';
    $('colour-by').value = initial;
    $('colour-by').addEventListener('change', (e) => colourBundle(e.target.value));
    colourBundle(initial);
    $('bundle-section').hidden = false;
    $('bundle-info').textContent = n + ' end-effector positions: starts and ends of ' + bundle.sampled_edges +
      ' of ' + bundle.edges + ' edges (seed ' + bundle.seed + ')' +
      (bundle.has_perturbation ? '' : '; no perturbation analysis in the bundle');
  }
  $('title').textContent = data.title;
  document.title = data.title;
  $('scene-info').textContent = 'robot ' + robot.name + ' (' + robot.shapes.length + ' shapes), environment ' +
    data.environment.name + ' (' + data.environment.obstacles.length + ' obstacles)';

  // ---- Render loop and its frame timer --------------------------------------------------
  const frames = {intervals: [], renderMs: [], last: null, count: 0};
  function frameStats() {
    const mean = (a) => (a.length ? a.reduce((x, y) => x + y, 0) / a.length : 0);
    const sorted = frames.intervals.slice().sort((x, y) => x - y);
    const interval = mean(frames.intervals);
    return {frames: frames.count, measured: sorted.length, mean_interval_ms: interval,
            fps: interval > 0 ? 1000 / interval : 0,
            p95_interval_ms: sorted.length ? sorted[Math.floor(0.95 * (sorted.length - 1))] : 0,
            max_interval_ms: sorted.length ? sorted[sorted.length - 1] : 0, mean_render_ms: mean(frames.renderMs)};
  }
  function animate(now) {
    if (frames.last !== null) {
      const dt = now - frames.last;
      frames.intervals.push(dt);
      if (frames.intervals.length > 600) frames.intervals.shift();
      if (play.playing) {
        setTime(play.time + play.speed * dt / 1000, true);
        if (play.time >= duration()) setTime(0, true);  // loop
      }
    }
    frames.last = now;
    const t0 = performance.now();
    stillLayers.render();
    frames.renderMs.push(performance.now() - t0);
    if (frames.renderMs.length > 600) frames.renderMs.shift();
    if (++frames.count % 30 === 0) $('fps').textContent = frameStats().fps.toFixed(0) + ' frames per second';
    requestAnimationFrame(animate);
  }

  // The robot's box on the page, in CSS pixels, for the screenshot check.
  function robotScreenBox() {
    scene.updateMatrixWorld(true);
    const shown = mainRobot.group.visible ? mainRobot : startGhost;
    const box = new THREE.Box3().setFromObject(shown.group);
    const rect = renderer.domElement.getBoundingClientRect();
    const xs = [], ys = [];
    for (const x of [box.min.x, box.max.x])
      for (const y of [box.min.y, box.max.y])
        for (const z of [box.min.z, box.max.z]) {
          const v = new THREE.Vector3(x, y, z).project(camera);
          xs.push(rect.left + (v.x + 1) / 2 * rect.width);
          ys.push(rect.top + (1 - v.y) / 2 * rect.height);
        }
    return {x0: Math.min(...xs), y0: Math.min(...ys), x1: Math.max(...xs), y1: Math.max(...ys)};
  }

  // The camera frames the robot (at zero) and every planned path, from behind the robot's
  // right shoulder: a shelf or a table in front of the robot is seen from the robot's side,
  // not from behind its back panel.
  function frameView() {
    const box = new THREE.Box3().setFromObject(mainRobot.group);
    const p = new THREE.Vector3();
    for (const tr of trajectories) {
      for (let k = 0; k < tr.pathPoints.length; k += 3)
        box.expandByPoint(p.fromArray(tr.pathPoints, k));
    }
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(0.4, box.getSize(new THREE.Vector3()).length() / 2);
    const distance = 1.1 * radius / Math.sin(THREE.Math.degToRad(camera.fov / 2));
    controls.target.copy(centre);
    camera.position.copy(centre).addScaledVector(new THREE.Vector3(-1.0, -1.1, 0.9).normalize(), distance);
    controls.update();
  }
  frameView();

  window.lazyboeView = {
    // Every link's pose at q: what the page draws, compared with lazyboe-robot fk by the tests.
    linkPoses: (q) => linkPoses(robot, q).map((p, i) => ({link: robot.links[i].name, position: p.p,
                                                          quaternion: quaternion(p.R)})),
    frameStats: frameStats,
    resetFrameStats() { frames.intervals = []; frames.renderMs = []; },
    robotScreenBox: robotScreenBox,
    // Robot and ghosts shown or hidden (the screenshot check compares both).
    showRobots(on) {
      stillLayers.changed();
      robotLayer.visible = on;
    },
    play() { if (!play.playing) $('play').click(); },
    setSpeed(s) { play.speed = s; },
    select: select,
    goalView: goalView,
    bundleShown: () => (bundlePoints ? bundlePoints.visible : null),
    // The share of the planned paths' points inside the view (the default camera frames them).
    pathsOnScreen() {
      camera.updateMatrixWorld();
      let inside = 0, all = 0;
      const p = new THREE.Vector3();
      for (const tr of trajectories) {
        for (let k = 0; k < tr.pathPoints.length; k += 3, ++all) {
          p.fromArray(tr.pathPoints, k).project(camera);
          inside += Math.abs(p.x) <= 1 && Math.abs(p.y) <= 1 ? 1 : 0;
        }
      }
      return all ? inside / all : 1;
    },
    messages: messages,
    renderer: rendererName,
    stillLayersCached: stillLayers.cached,
    renderScale: renderScale,
  };
  stillLayers.render();
  body.setAttribute('data-robot-shapes', String(robot.shapes.length));
  body.setAttribute('data-robot-meshes', String(robot.shapes.filter((s) => s.display).length));
  body.setAttribute('data-robot-visuals', String((robot.visuals || []).length));
  body.setAttribute('data-obstacles', String(data.environment.obstacles.length));
  body.setAttribute('data-obstacle-types', data.environment.obstacles.map((o) => o.type).join(' '));
  body.setAttribute('data-trajectories', String(trajectories.length));
  body.setAttribute('data-failures', String(failures.length));
  body.setAttribute('data-bundle-points', String(bundle ? bundle.points.length / 3 : 0));
  body.setAttribute('data-messages', String(messages.length));
  body.setAttribute('data-load-ms', performance.now().toFixed(1));
  body.setAttribute('data-status', 'ready');
  requestAnimationFrame(animate);
})();
