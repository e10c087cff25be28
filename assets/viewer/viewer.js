// Replays one recorded grasping episode (JSON in the #episode element) with three.js.
// World frame: z up, table top at z = 0, metres. Poses are [x, y, z, qx, qy, qz, qw].
// URL hash: #frame=N shows frame N paused (N may be "end"); otherwise the episode plays.
// #noui hides the panels (for screenshots).
(function () {
  "use strict";
  var ep = JSON.parse(document.getElementById("episode").textContent);
  var $ = function (id) { return document.getElementById(id); };
  var FINGERS = ["FF", "MF", "RF", "LF", "TH"];
  var LEVEL_COLOURS = ["#2166ac", "#67a9cf", "#d1e5f0", "#fddbc7", "#ef8a62", "#b2182b"];

  $("title").textContent = ep.agent + " on " + ep.object + " (seed " + ep.seed + ")";
  var s = ep.summary;
  $("outcome").innerHTML = (s.success ? "<b style='color:#2ca02c'>success</b>"
    : "<b style='color:#d62728'>failure</b>") + ", " + s.steps + " control steps" +
    (s.lifted ? ", lifted" : ", not lifted") + (s.physics_failure ? ", physics failure" : "");

  if (!ep.frames.length) {
    $("msg").textContent = "no frames recorded";
    return;
  }
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    $("msg").textContent = "WebGL is not available: " + e;
    return;
  }
  var view = $("view");
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f0);
  var camera = new THREE.PerspectiveCamera(40, 1, 0.01, 20);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 0.75));
  var sun = new THREE.DirectionalLight(0xffffff, 0.7);
  sun.position.set(0.5, -0.8, 1.5);
  scene.add(sun);

  // Table top (z = 0) with a 5 cm grid.
  var table = new THREE.Mesh(new THREE.BoxGeometry(0.8, 0.8, 0.01),
    new THREE.MeshLambertMaterial({ color: 0xc8c0b0 }));
  table.position.set(0, 0, -0.005);
  scene.add(table);
  var grid = new THREE.GridHelper(0.8, 16, 0x999999, 0xaaaaaa);
  grid.rotation.x = Math.PI / 2;
  grid.position.z = 0.0005;
  scene.add(grid);

  function quatFromYTo(a, b) {
    var d = new THREE.Vector3(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
    var q = new THREE.Quaternion();
    if (d.length() > 1e-9) {
      q.setFromUnitVectors(new THREE.Vector3(0, 1, 0), d.normalize());
    }
    return q;
  }

  // A mesh for one shape in its own frame.
  function shapeMesh(g, material) {
    var m;
    switch (g.kind) {
      case "box":
        return new THREE.Mesh(new THREE.BoxGeometry(2 * g.half[0], 2 * g.half[1], 2 * g.half[2]), material);
      case "sphere":
        return new THREE.Mesh(new THREE.SphereGeometry(g.radius, 16, 12), material);
      case "cylinder":
        return new THREE.Mesh(new THREE.CylinderGeometry(g.radius, g.radius, 2 * g.half_height, 20), material);
      case "capsule": {
        var len = Math.hypot(g.b[0] - g.a[0], g.b[1] - g.a[1], g.b[2] - g.a[2]);
        m = new THREE.Mesh(new THREE.CapsuleGeometry(g.radius, len, 6, 16), material);
        m.position.set((g.a[0] + g.b[0]) / 2, (g.a[1] + g.b[1]) / 2, (g.a[2] + g.b[2]) / 2);
        m.quaternion.copy(quatFromYTo(g.a, g.b));
        var wrap = new THREE.Group();
        wrap.add(m);
        return wrap;
      }
      case "mesh": {
        var geo = new THREE.BufferGeometry();
        var pos = new Float32Array(g.vertices.length * 3);
        for (var i = 0; i < g.vertices.length; i++) {
          pos[3 * i] = g.vertices[i][0];
          pos[3 * i + 1] = g.vertices[i][1];
          pos[3 * i + 2] = g.vertices[i][2];
        }
        var idx = [];
        for (var k = 0; k < g.triangles.length; k++) {
          idx.push(g.triangles[k][0], g.triangles[k][1], g.triangles[k][2]);
        }
        geo.setAttribute("position", new THREE.BufferAttribute(pos, 3));
        geo.setIndex(idx);
        geo = geo.toNonIndexed();
        geo.computeVertexNormals();
        return new THREE.Mesh(geo, material);
      }
    }
    return new THREE.Group();
  }

  function setPose(obj, p) {
    obj.position.set(p[0], p[1], p[2]);
    obj.quaternion.set(p[3], p[4], p[5], p[6]);
  }

  // Hand: one object per collider; tactile colliders get their own material.
  var handMat = new THREE.MeshLambertMaterial({ color: 0x5b7fa6 });
  var tipMats = FINGERS.map(function () { return new THREE.MeshLambertMaterial({ color: 0x5b7fa6 }); });
  var hand = ep.hand_geometry.map(function (g, i) {
    var f = ep.hand_tactile_fingers[i];
    var o = shapeMesh(g, f === null || f === undefined ? handMat : tipMats[f]);
    scene.add(o);
    return o;
  });

  // Object: a group in its body frame.
  var objMat = new THREE.MeshLambertMaterial({ color: 0xe8902a });
  var object = new THREE.Group();
  ep.object_geometry.forEach(function (ps) {
    var o = shapeMesh(ps.shape, objMat);
    var holder = new THREE.Group();
    setPose(holder, ps.pose);
    holder.add(o);
    object.add(holder);
  });
  scene.add(object);

  // Orbit camera around the object's start: drag to turn, wheel to zoom.
  var o0 = ep.frames[0].object;
  var target = new THREE.Vector3(o0[0], o0[1], o0[2] + 0.08);
  var orbit = { az: -2.1, el: 0.35, r: 0.75 };
  function placeCamera() {
    camera.position.set(
      target.x + orbit.r * Math.cos(orbit.el) * Math.cos(orbit.az),
      target.y + orbit.r * Math.cos(orbit.el) * Math.sin(orbit.az),
      target.z + orbit.r * Math.sin(orbit.el));
    camera.lookAt(target);
  }
  var drag = null;
  renderer.domElement.addEventListener("pointerdown", function (e) { drag = [e.clientX, e.clientY]; });
  window.addEventListener("pointerup", function () { drag = null; });
  window.addEventListener("pointermove", function (e) {
    if (!drag) return;
    orbit.az -= (e.clientX - drag[0]) * 0.01;
    orbit.el = Math.max(-0.2, Math.min(1.5, orbit.el + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY];
    placeCamera();
    draw();
  });
  renderer.domElement.addEventListener("wheel", function (e) {
    e.preventDefault();
    orbit.r = Math.max(0.1, Math.min(3, orbit.r * Math.exp(e.deltaY * 0.001)));
    placeCamera();
    draw();
  }, { passive: false });

  function resize() {
    var w = view.clientWidth || window.innerWidth, h = view.clientHeight || window.innerHeight;
    renderer.setSize(w, h);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
    draw();
  }

  // The control record in force at simulated time t.
  function controlAt(t) {
    var c = null;
    for (var i = 0; i < ep.control.length; i++) {
      if (ep.control[i].t <= t + 1e-9) c = ep.control[i];
    }
    return c;
  }

  var slider = $("slider");
  slider.max = String(ep.frames.length - 1);
  var current = 0;
  function show(i) {
    current = Math.max(0, Math.min(ep.frames.length - 1, i));
    var f = ep.frames[current];
    for (var k = 0; k < hand.length; k++) setPose(hand[k], f.hand[k]);
    setPose(object, f.object);
    for (var n = 0; n < 5; n++) tipMats[n].color.set(f.tactile[n] ? 0xd62728 : 0x5b7fa6);
    slider.value = String(current);
    $("time").textContent = "t = " + f.t.toFixed(3) + " s (physics step " + f.physics_step +
      ", frame " + (current + 1) + "/" + ep.frames.length + "), lift " + (1000 * f.lift).toFixed(0) + " mm";
    $("stage").textContent = f.stage;
    $("tactile").innerHTML = FINGERS.map(function (name, n) {
      return "<span class='bit" + (f.tactile[n] ? " on" : "") + "'>" + name + "</span>";
    }).join("");
    $("torque").innerHTML = f.torque_level.map(function (l, n) {
      return "<span class='lvl' title='actuator " + n + ": level " + l + "' style='background:" +
        LEVEL_COLOURS[Math.max(0, Math.min(5, l))] + "'></span>";
    }).join("") + " <span class='mono'>" + f.torque_level.join("") + "</span>";
    var c = controlAt(f.t);
    $("action").textContent = c && c.action ? ("step " + c.step + ": [" + c.action.map(function (x) {
      return x.toFixed(2);
    }).join(", ") + "]" + (c.lift ? " lift" : "") + ", reward " + c.reward.toFixed(3)) : "-";
    draw();
  }
  function draw() { renderer.render(scene, camera); }

  var playing = true, speed = 1, last = null, clock = 0;
  $("play").addEventListener("click", function () {
    playing = !playing;
    $("play").textContent = playing ? "pause" : "play";
    if (playing && current >= ep.frames.length - 1) { show(0); }
    last = null;
  });
  slider.addEventListener("input", function () { show(parseInt(slider.value, 10)); });
  $("speed").addEventListener("change", function () { speed = parseFloat($("speed").value); });
  function tick(now) {
    if (playing && last !== null) {
      clock = ep.frames[current].t + speed * (now - last) / 1000;
      var i = current;
      while (i + 1 < ep.frames.length && ep.frames[i + 1].t <= clock) i++;
      if (i !== current) show(i);
      if (current >= ep.frames.length - 1) {
        playing = false;
        $("play").textContent = "play";
      }
    }
    last = now;
    requestAnimationFrame(tick);
  }

  var m = /frame=(\w+)/.exec(window.location.hash);
  if (/noui/.test(window.location.hash)) {
    $("panel").style.display = "none";
    $("controls").style.display = "none";
  }
  placeCamera();
  window.addEventListener("resize", resize);
  resize();
  if (m) {
    playing = false;
    $("play").textContent = "play";
    show(m[1] === "end" ? ep.frames.length - 1 : parseInt(m[1], 10) || 0);
  } else {
    show(0);
  }
  requestAnimationFrame(tick);
})();
