// The front end of volux.show(): the frame as an <img>, the mouse sent to the kernel as
// drag and wheel messages (left button orbits, right button or shift pans, the wheel
// zooms). While a message's frame is being drawn the next drag is held and merged, so a
// slow kernel gets one message per frame, not a queue.
function render({ model, el }) {
  const root = document.createElement("div");
  root.className = "volux-widget";
  root.style.position = "relative";
  root.style.display = "inline-block";
  root.style.userSelect = "none";
  const img = document.createElement("img");
  img.draggable = false;
  img.style.cursor = "grab";
  img.style.background = "#000";
  img.style.display = "block";
  const status = document.createElement("div");
  status.className = "volux-status";
  status.style.font = "12px sans-serif";
  status.style.color = "#888";
  root.append(img, status);
  el.append(root);

  let url = null;
  function show() {
    const png = model.get("png");
    if (png && png.byteLength > 0) {
      const blob = new Blob([png], { type: "image/png" });
      if (url) URL.revokeObjectURL(url);
      url = URL.createObjectURL(blob);
      img.src = url;
    }
    img.style.width = model.get("width") + "px";
    img.style.height = model.get("height") + "px";
    status.textContent = model.get("status");
    waiting = false;
    flush();
  }

  // One message in flight; drags that arrive meanwhile are summed.
  let waiting = false;
  let held = null;
  function send(msg) {
    if (waiting && msg.phase === "move") {
      if (held && held.type === msg.type && held.mode === msg.mode) {
        held.dx += msg.dx || 0;
        held.dy += msg.dy || 0;
        held.delta = (held.delta || 0) + (msg.delta || 0);
      } else {
        held = { ...msg };
      }
      return;
    }
    waiting = true;
    model.send(msg);
  }
  function flush() {
    if (held && !waiting) {
      const m = held;
      held = null;
      send(m);
    }
  }

  let last = null;
  let mode = "orbit";
  img.addEventListener("pointerdown", (e) => {
    last = [e.clientX, e.clientY];
    mode = e.button === 2 || e.shiftKey ? "pan" : "orbit";
    img.setPointerCapture(e.pointerId);
    img.style.cursor = "grabbing";
    e.preventDefault();
  });
  img.addEventListener("pointermove", (e) => {
    if (!last) return;
    const dx = e.clientX - last[0];
    const dy = e.clientY - last[1];
    last = [e.clientX, e.clientY];
    if (dx !== 0 || dy !== 0) send({ type: "drag", mode, dx, dy, phase: "move" });
  });
  function end(e) {
    if (!last) return;
    last = null;
    img.style.cursor = "grab";
    held = null;
    waiting = false;
    send({ type: "drag", mode, dx: 0, dy: 0, phase: "end" });
  }
  img.addEventListener("pointerup", end);
  img.addEventListener("pointercancel", end);
  img.addEventListener("contextmenu", (e) => e.preventDefault());
  img.addEventListener(
    "wheel",
    (e) => {
      e.preventDefault();
      send({ type: "wheel", delta: e.deltaY, phase: "move" });
    },
    { passive: false }
  );
  let wheelTimer = null;
  img.addEventListener("wheel", () => {
    clearTimeout(wheelTimer);
    wheelTimer = setTimeout(() => send({ type: "wheel", delta: 0, phase: "end" }), 250);
  });

  model.on("change:png", show);
  model.on("change:status", () => (status.textContent = model.get("status")));
  show();
  return () => {
    if (url) URL.revokeObjectURL(url);
  };
}
export default { render };
