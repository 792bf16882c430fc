// Glue between rbm_nb and meshcat's bundled viewer (MeshCat.Viewer).
// Used by the live page served by rbm_nb.scene.server and inlined in the
// self-contained HTML exports written by Scene.to_html.
(function () {
  "use strict";

  function createViewer(pane) {
    var viewer = new MeshCat.Viewer(pane);
    // Recordings span tens of metres; meshcat's default far plane is 100 m.
    viewer.camera.far = 5000;
    viewer.camera.updateProjectionMatrix();
    return viewer;
  }

  // Place the camera given in scene (z-up) coordinates. meshcat turns its
  // whole three.js scene to make z point up, and its camera lives in a node
  // under /Cameras/default/rotated that OrbitControls works in: both points go
  // scene -> three.js world -> that node.
  function applyCamera(viewer, cam) {
    var THREE = MeshCat.THREE;
    var parent = viewer.camera.parent;
    if (!parent) { return; }
    viewer.scene.updateMatrixWorld(true);
    function toCameraNode(point) {
      return parent.worldToLocal(viewer.scene.localToWorld(new THREE.Vector3().fromArray(point)));
    }
    var position = toCameraNode(cam.position);
    var target = toCameraNode(cam.target);
    viewer.camera.position.copy(position);
    viewer.controls.target.copy(target);
    viewer.controls.update();
    viewer.set_dirty();
  }

  function handleText(viewer, text) {
    var msg = JSON.parse(text);
    if (msg.type === "rbm_reset") {
      viewer.delete_path(["rbm"]);
    } else if (msg.type === "rbm_camera") {
      applyCamera(viewer, msg);
    }
    viewer.set_dirty();
  }

  function websocketUrl() {
    var url = new URL("ws", window.location.href);
    url.protocol = window.location.protocol === "https:" ? "wss:" : "ws:";
    url.search = "";
    url.hash = "";
    return url.toString();
  }

  function connectLive(pane, statusElement) {
    var viewer = createViewer(pane);
    var stats = { connected: false, messages: 0, url: websocketUrl(), reconnects: 0 };
    window.rbmViewerStats = stats;
    window.rbmViewerInstance = viewer;
    var delay = 250;

    function status(text) {
      if (statusElement) { statusElement.textContent = text; }
    }

    function open() {
      var ws = new WebSocket(stats.url);
      ws.binaryType = "arraybuffer";
      ws.onopen = function () {
        stats.connected = true;
        delay = 250;
        status("live");
      };
      ws.onmessage = function (event) {
        stats.messages += 1;
        if (typeof event.data === "string") {
          handleText(viewer, event.data);
        } else {
          viewer.handle_command_bytearray(new Uint8Array(event.data));
        }
      };
      ws.onclose = function (event) {
        stats.connected = false;
        if (event.code === 4000 || event.code === 4004) {
          status("scene closed");
          return;
        }
        status("disconnected, retrying");
        stats.reconnects += 1;
        setTimeout(open, delay);
        delay = Math.min(delay * 2, 5000);
      };
    }
    open();
    return viewer;
  }

  function decodeBase64(text) {
    var raw = atob(text);
    var bytes = new Uint8Array(raw.length);
    for (var i = 0; i < raw.length; i++) { bytes[i] = raw.charCodeAt(i); }
    return bytes;
  }

  function floats(text) {
    var bytes = decodeBase64(text);
    return new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
  }

  function formatTime(t, data) {
    if (data.datetime) {
      var iso = new Date(data.t0 * 1000 + t * 1000).toISOString();
      return iso.replace("T", " ").replace("Z", "");
    }
    return (data.t0 + t).toFixed(3) + " s";
  }

  // Build meshcat animation clips from compact float32 tracks and add our own
  // play / pause / time controls.
  function loadExport(pane, data, controls) {
    var viewer = createViewer(pane);
    window.rbmViewerInstance = viewer;
    data.commands.forEach(function (cmd) {
      viewer.handle_command_bytearray(decodeBase64(cmd));
    });
    var animations = data.tracks.map(function (track) {
      var tracks = [];
      var times = floats(track.times);
      if (track.position) {
        tracks.push({ name: ".position", type: "vector3", times: times, values: floats(track.position) });
      }
      if (track.quaternion) {
        tracks.push({ name: ".quaternion", type: "quaternion", times: times, values: floats(track.quaternion) });
      }
      if (track.scale) {
        tracks.push({ name: ".scale", type: "vector3", times: times, values: floats(track.scale) });
      }
      if (track.visible) {
        tracks.push({ name: ".visible", type: "bool", times: track.visible.times, values: track.visible.values });
      }
      return { path: track.path, clip: { fps: 1, name: "default", tracks: tracks } };
    });
    if (animations.length > 0) {
      viewer.handle_command({
        type: "set_animation",
        animations: animations,
        options: { play: false, repetitions: Infinity },
      });
    }
    if (data.camera) { applyCamera(viewer, data.camera); }

    var animator = viewer.animator;
    var duration = data.duration;
    function currentTime() {
      if (animator.actions.length === 0) { return 0; }
      return animator.actions[0].time;
    }
    var state = {
      viewer: viewer,
      duration: duration,
      play: function () { animator.play(); sync(); },
      pause: function () { animator.pause(); sync(); },
      seek: function (t) {
        animator.seek(Math.max(0, Math.min(duration, t)));
        viewer.render();
        sync();
      },
      time: currentTime,
    };
    window.rbmExport = state;

    function sync() {
      var t = currentTime();
      controls.readout.textContent = formatTime(t, data);
      if (!controls.dragging) {
        controls.slider.value = duration > 0 ? String(t / duration * 1000) : "0";
      }
      controls.play.textContent = animator.playing ? "\u275a\u275a" : "\u25b6";
    }
    controls.play.addEventListener("click", function () {
      if (animator.playing) { state.pause(); } else { state.play(); }
    });
    controls.slider.addEventListener("input", function () {
      controls.dragging = true;
      state.seek(Number(controls.slider.value) / 1000 * duration);
    });
    controls.slider.addEventListener("change", function () { controls.dragging = false; });
    (function loop() {
      if (animator.playing) { sync(); }
      requestAnimationFrame(loop);
    })();
    state.seek(0);
    if (data.autoplay) { state.play(); }
    return state;
  }

  window.rbmViewer = {
    createViewer: createViewer,
    applyCamera: applyCamera,
    connectLive: connectLive,
    loadExport: loadExport,
  };
})();
