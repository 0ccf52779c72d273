// rik browser teleop station: streams the cameras, shows the status, sends keyboard / gamepad / button input.
// Protocol: see rik/web/teleop.py. Plain JavaScript, no build step.
"use strict";

(function () {
  const variant = decodeURIComponent(location.pathname.replace(/\/+$/, "").split("/").pop());
  const robotParam = new URLSearchParams(location.search).get("robot"); // null: the server's robot
  // ?replay=<episode id> (the episodes page's link): once this tab controls the ready station, replay that episode
  const replayParam = new URLSearchParams(location.search).get("replay");
  let replaySent = false;
  const $ = (id) => document.getElementById(id);
  const root = $("station");
  // The status arrives about 20 times a second and the input is read every animation frame: these write to the page
  // only what changed, so that a station nobody moves does not restyle and repaint its page 20-60 times a second
  // (a fifth of a core in Chromium; a change of the same value is still a change to the browser).
  function setText(el, text) { if (el.textContent !== text) el.textContent = text; }
  function setProp(el, name, value) { if (el[name] !== value) el[name] = value; }
  function setData(values) {
    for (const [name, value] of Object.entries(values)) {
      const text = String(value);
      if (root.dataset[name] !== text) root.dataset[name] = text;
    }
  }
  const DEADZONE = 0.15;
  const SEND_PERIOD = 33; // ms: inputs ~30 Hz while anything is held
  const PAD = [ // what the standard-mapping gamepad does (shown on the page)
    ["left stick", "left / right, towards / away"],
    ["right stick", "up / down (y), yaw (x)"],
    ["LT / L2 (hold) + right stick", "orbit the front view instead (R3: put it back)"],
    ["d-pad", "pitch (up / down), roll (left / right)"],
    ["right trigger (RT / R2)", "grip: the harder, the tighter (analog)"],
    ["A / cross", "close / open the gripper"],
    ["LB / L1 (hold)", "fine motion (x0.25)"],
    ["Start / Options", "save the episode"],
    ["Back / Share", "discard the episode"],
    ["Y / triangle", "replay the last saved episode"],
  ];
  const PAD_BUTTONS = {0: "toggle_grip", 9: "save", 8: "discard", 3: "replay"};
  const ORBIT_BUTTON = 6;   // LT / L2 held: the right stick orbits the front view
  const ORBIT_RESET = 11;   // R3 (the right stick pressed): the front view back
  const ORBIT_SPEED = 90;   // degrees per second at full deflection

  let keymap = null;
  let ws = null;
  let seq = 0;
  let lastSent = null;
  let lastSentAt = 0;
  let lastTrigger = 0;
  let padPrev = [];
  let orbitAt = 0;     // when the last orbit turn was sent (ms)
  let virtualPad = null;
  let status = null;
  let lastStep = 0;
  const held = new Set();      // keyboard codes held
  const pointerHeld = new Set(); // on-screen hold buttons held
  const frames = {front: 0, wrist: 0};

  $("variant").textContent = variant;
  root.dataset.variant = variant;
  document.title = "rik teleop " + variant;

  // ---- keymap -------------------------------------------------------------------------------------------------
  fetch("/teleop/keymap.json").then((r) => r.json()).then((k) => {
    keymap = k;
    const table = $("keymap");
    for (const [keys, does] of k.rows) {
      const tr = table.insertRow();
      tr.insertCell().textContent = keys;
      tr.insertCell().textContent = does;
    }
    const hold = $("hold");
    for (const b of k.motion) {
      const btn = document.createElement("button");
      btn.textContent = b.label + ": " + b.does;
      btn.dataset.code = b.code;
      btn.id = "hold-" + b.code;
      const release = () => { pointerHeld.delete(b.code); btn.classList.remove("held"); };
      btn.addEventListener("pointerdown", (e) => {
        pointerHeld.add(b.code); btn.classList.add("held");
        try { btn.setPointerCapture(e.pointerId); } catch (_) { /* synthetic events */ }
        e.preventDefault();
      });
      for (const ev of ["pointerup", "pointercancel", "lostpointercapture"]) btn.addEventListener(ev, release);
      hold.appendChild(btn);
    }
  });
  const padTable = $("padmap");
  for (const [what, does] of PAD) {
    const tr = padTable.insertRow();
    tr.insertCell().textContent = what;
    tr.insertCell().textContent = does;
  }

  // ---- connection ---------------------------------------------------------------------------------------------
  function send(obj) {
    if (ws && ws.readyState === WebSocket.OPEN) { ws.send(JSON.stringify(obj)); return true; }
    return false;
  }
  function command(name) { send({type: "command", name: name}); }

  function connect() {
    const proto = location.protocol === "https:" ? "wss:" : "ws:";
    const query = robotParam ? "?robot=" + encodeURIComponent(robotParam) : "";
    ws = new WebSocket(proto + "//" + location.host + "/teleop/" + encodeURIComponent(variant) + "/ws" + query);
    ws.binaryType = "arraybuffer";
    let opened = false;
    ws.onopen = () => {
      opened = true;
      $("conn").textContent = "connected";
      root.dataset.connected = "true";
      sendSize();
    };
    ws.onclose = () => {
      // a handshake refused (a restarted server has a new launch token) or a server that is gone: keep trying
      $("conn").textContent = opened ? "disconnected: reconnecting..." : "cannot connect: if rik was restarted, " +
        "open the address it printed (its token is new); retrying...";
      root.dataset.connected = "false";
      setTimeout(connect, 1000);
    };
    ws.onmessage = (ev) => {
      if (typeof ev.data === "string") { showStatus(JSON.parse(ev.data)); return; }
      showFrame(ev.data);
    };
  }

  function showFrame(buf) {
    const view = new DataView(buf);
    const n = view.getUint32(0, false);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
    const img = $("cam-" + header.camera);
    if (!img) return;
    const url = URL.createObjectURL(new Blob([new Uint8Array(buf, 4 + n)], {type: "image/jpeg"}));
    const old = img.dataset.url;
    img.onload = () => { if (old) URL.revokeObjectURL(old); };
    img.dataset.url = url;
    img.src = url;
    img.dataset.step = header.step;
    img.dataset.seq = header.seq;
    img.dataset.t = header.t;
    frames[header.camera] = (frames[header.camera] || 0) + 1;
  }

  function pct(x) { return (100 * x).toFixed(0) + " %"; }
  function showStatus(st) {
    status = st;
    if (replayParam && !replaySent && st.ready && st.role === "controller") {
      replaySent = send({type: "command", name: "replay", episode: replayParam});
    }
    setData({ready: !!st.ready, role: st.role || "", paused: !!st.paused, draft: st.draft || "", seq: st.seq,
      replaying: !!st.replay});
    if (st.view) setData({viewAzimuth: st.view.azimuth, viewElevation: st.view.elevation});
    if (st.robot) {
      setData({robot: st.robot});
      setText($("robot"), "with " + st.robot);
      setText($("st-robot"), st.robot);
    }
    const role = $("role");
    setText(role, st.role === "controller" ? "you control this session" : st.role === "watcher" ? "watching" : "");
    setProp(role, "className", "role " + (st.role || ""));
    setProp($("btn-take"), "hidden", st.role === "controller");
    const s = st.session;
    if (s) {
      setData({episode: s.episode, state: s.state, steps: s.steps, opening: s.opening, grip: s.grip,
        ahead: s.handle.ahead, left: s.handle.left, up: s.handle.up, x: s.pose[0], y: s.pose[1], z: s.pose[2],
        roll: s.pose[5], lastSaved: s.last_saved || ""});
      setText($("st-episode"), s.episode);
      setText($("st-state"), st.replay ? "replaying " + st.replay.episode + " (" + st.replay.row + "/" +
        st.replay.rows + ")" : st.paused ? "paused (draft kept)" : s.state);
      setText($("st-time"), s.time.toFixed(1));
      setText($("st-time-left"), s.time_left === null ? "no limit" : s.time_left.toFixed(1) + " s left");
      const opening = st.replay ? st.replay.opening : s.opening;  // a replay shows the replayed episode's opening
      setData({shownOpening: opening});
      setText($("st-opening"), st.replay ? pct(opening) + " (replayed)" :
        pct(s.opening) + " (max " + pct(s.max_opening) + ")");
      const bar = $("opening-bar"), width = Math.max(0, Math.min(100, 100 * opening)).toFixed(1);
      if (parseFloat(bar.style.width) !== Number(width)) bar.style.width = width + "%";  // the browser writes 12%
      setText($("st-grip"), s.grip + " (" + s.grip_command.toFixed(2) + ")");
      setData({grasp: s.grasp, blocked: s.blocked, motion: s.motion.on_path ? "path" : "frame",
        motionMode: s.motion.mode});
      const grasp = $("st-grasp");
      setText(grasp, s.grasp === "slipped" ? "slipped: open (Space) and grasp again" : s.grasp);
      setProp(grasp, "className", "grasp " + s.grasp);
      setProp($("st-blocked"), "hidden", !s.blocked);
      const f = s.front_position;
      setData({frontAngle: f.angle_deg === undefined ? "" : f.angle_deg});
      setText($("st-front"), f.angle_deg === undefined ? f.kind + " out " + f.travel_mm.toFixed(0) + " mm" :
        f.kind + " at " + f.angle_deg.toFixed(0) + " deg");
      setText($("st-yaw"), s.yaw_deg.toFixed(0) + " deg");
      setText($("st-motion"), s.motion.mode === "frame" ? "frame-fixed" : s.motion.on_path ||
        s.grasp === "holding" ? "along the front's path (W / S)" : "frame-fixed until the handle is held");
      const hint = $("hint");
      setProp(hint, "hidden", !s.hint || s.steps > 0);
      setText(hint, s.hint ? "How to grasp this handle: " + s.hint : "");
      const h = s.handle;
      setText($("st-handle"), h.ahead.toFixed(3) + " m ahead, " + h.left.toFixed(3) + " m left, " +
        h.up.toFixed(3) + " m up");
      setText($("st-roll"), s.roll_deg.toFixed(0) + " deg");
      setText($("st-last-saved"), s.last_saved || "-");
    } else {
      setData({state: st.error ? "error" : "building"});
      setText($("st-state"), st.error ? "error" : "building the variant...");
    }
    setText($("st-fps"), st.fps ? st.fps + " frames/s" : "still (a frame is sent when the scene changes)");
    if (st.size) setText($("st-size"), st.size[0] + "x" + st.size[1]);
    // banner: an error, then this tab's notice, then the station's and the session's last message
    let text = "", level = "info";
    if (st.error) { text = st.error; level = "error"; }
    else if (!st.ready) { text = "building the variant..."; }
    else if (st.notice) { text = st.notice; level = "warn"; }
    else if (st.message) { text = st.message; }
    else if (s && s.state === "time up") { text = "time is up: save (Enter) or discard (Backspace)"; level = "warn"; }
    else if (s && s.message) { text = s.message; }
    const banner = $("banner");
    setProp(banner, "hidden", !text);
    setText(banner, text);
    setProp(banner, "className", "banner " + level);
    if (banner.dataset.level !== level) banner.dataset.level = level;
    setProp($("draft-offer"), "hidden", !(st.paused && st.role === "controller"));
    if (st.draft) setText($("draft-text"), "The connection was lost mid-episode; the episode was kept as a " +
      "draft (" + st.draft + "). Continue it, save it or discard it.");
  }

  function sendSize() {
    const [w, h] = $("size").value.split("x").map(Number);
    send({type: "size", width: w, height: h});
  }
  $("size").addEventListener("change", sendSize);

  // ---- buttons ------------------------------------------------------------------------------------------------
  for (const btn of document.querySelectorAll("button[data-command]")) {
    btn.addEventListener("click", () => { command(btn.dataset.command); btn.blur(); });
  }

  // ---- the front view: drag to orbit it, double-click to put it back ----------------------------------------------
  const frontView = $("cam-front");
  let drag = null;
  frontView.addEventListener("pointerdown", (e) => {
    drag = {x: e.clientX, y: e.clientY};
    frontView.setPointerCapture(e.pointerId);
    e.preventDefault();
  });
  frontView.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) < 2) return;
    drag = {x: e.clientX, y: e.clientY};
    send({type: "view", azimuth: -0.4 * dx, elevation: -0.4 * dy});
  });
  for (const ev of ["pointerup", "pointercancel"]) frontView.addEventListener(ev, () => { drag = null; });
  frontView.addEventListener("dblclick", () => send({type: "view", reset: true}));

  // ---- keyboard -----------------------------------------------------------------------------------------------
  const COMMAND_CODES = {Space: "toggle_grip", KeyM: "toggle_motion", Enter: "save", NumpadEnter: "save",
    Backspace: "discard"};
  function handled(code) {
    return code in COMMAND_CODES || code.startsWith("Arrow") || code.startsWith("Shift") ||
      (keymap && keymap.motion.some((b) => b.code === code));
  }
  window.addEventListener("keydown", (e) => {
    if (e.target && e.target.tagName === "SELECT") return;
    if (!handled(e.code)) return;
    e.preventDefault();
    if (e.code in COMMAND_CODES) { if (!e.repeat) command(COMMAND_CODES[e.code]); return; }
    held.add(e.code);
    step();
  });
  window.addEventListener("keyup", (e) => {
    if (handled(e.code)) e.preventDefault();
    held.delete(e.code);
    step();
  });
  window.addEventListener("blur", () => { held.clear(); pointerHeld.clear(); step(); });

  // ---- gamepad ------------------------------------------------------------------------------------------------
  function readPad() {
    if (virtualPad) return virtualPad;
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    for (const p of pads) if (p && p.connected) return p;
    return null;
  }
  function dz(v) {
    v = Number(v) || 0;
    if (Math.abs(v) < DEADZONE) return 0;
    return Math.sign(v) * (Math.abs(v) - DEADZONE) / (1 - DEADZONE);
  }
  function pressed(pad, i) { const b = pad.buttons && pad.buttons[i]; return !!(b && (b.pressed || b.value > 0.5)); }

  // ---- input --------------------------------------------------------------------------------------------------
  function currentInput() {
    const axes = [0, 0, 0, 0, 0, 0];
    let fine = held.has("ShiftLeft") || held.has("ShiftRight") || $("fine").checked;
    if (keymap) {
      for (const b of keymap.motion) if (held.has(b.code) || pointerHeld.has(b.code)) axes[b.axis] += b.sign;
    }
    let grip = null;
    const pad = readPad();
    if (pad) {
      const a = pad.axes || [];
      axes[0] -= dz(a[0]); axes[1] += dz(a[1]);
      if (pressed(pad, ORBIT_BUTTON)) orbit(dz(a[2]), dz(a[3]));
      else { axes[2] -= dz(a[3]); axes[4] -= dz(a[2]); orbitAt = 0; }
      if (pressed(pad, ORBIT_RESET) && !padPrev[ORBIT_RESET]) send({type: "view", reset: true});
      padPrev[ORBIT_RESET] = pressed(pad, ORBIT_RESET);
      if (pressed(pad, 12)) axes[3] -= 1;
      if (pressed(pad, 13)) axes[3] += 1;
      if (pressed(pad, 14)) axes[5] += 1;
      if (pressed(pad, 15)) axes[5] -= 1;
      if (pressed(pad, 4)) fine = true;
      const rt = pad.buttons && pad.buttons[7] ? Number(pad.buttons[7].value) || 0 : 0;
      if (Math.abs(rt - lastTrigger) > 0.02) { grip = rt; lastTrigger = rt; }
      for (const [i, name] of Object.entries(PAD_BUTTONS)) {
        const now = pressed(pad, Number(i));
        if (now && !padPrev[i]) command(name);
        padPrev[i] = now;
      }
      setText($("pad-state"), "gamepad: " + (pad.id || "connected"));
    } else {
      setText($("pad-state"), "no gamepad (press a button on it to connect)");
    }
    return {axes: axes.map((v) => Math.round(Math.max(-1, Math.min(1, v)) * 1000) / 1000), grip: grip, fine: fine};
  }

  // the right stick's orbit of the front view (LT held): turns sent at most every SEND_PERIOD, by the time since the
  // last one, so the view turns at ORBIT_SPEED whatever the frame rate; stick right turns as a drag to the right
  function orbit(x, y) {
    const now = performance.now();
    if (!x && !y) { orbitAt = 0; return; }
    if (!orbitAt) { orbitAt = now; return; }
    if (now - orbitAt < SEND_PERIOD) return;
    const dt = Math.min(now - orbitAt, 200) / 1000;
    orbitAt = now;
    send({type: "view", azimuth: -ORBIT_SPEED * x * dt, elevation: -ORBIT_SPEED * y * dt});
  }

  function step() {
    lastStep = performance.now();
    const inp = currentInput();
    const moving = inp.axes.some((v) => v !== 0);
    const key = JSON.stringify([inp.axes, inp.fine]);
    const now = performance.now();
    if (key !== lastSent || inp.grip !== null || (moving && now - lastSentAt >= SEND_PERIOD)) {
      if (send({type: "input", seq: ++seq, axes: inp.axes, grip: inp.grip, fine: inp.fine})) {
        lastSent = key;
        lastSentAt = now;
        root.dataset.sentSeq = seq;
      }
    }
  }
  function frame() { step(); requestAnimationFrame(frame); }
  requestAnimationFrame(frame);
  setInterval(() => { if (performance.now() - lastStep > 100) step(); }, 50); // when animation frames pause

  window.rikTest = {
    setGamepad(state) { virtualPad = state ? {id: "rikTest virtual gamepad", connected: true, ...state} : null; step(); },
    status() { return status; },
    frames: frames,
  };
  connect();
})();
