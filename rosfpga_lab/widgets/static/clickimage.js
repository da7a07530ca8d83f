// A clickable image (anywidget ESM): shows `png` (bytes) at `display_width` pixels, sharp
// (no smoothing), and reports a click as `clicked` = [x, y] in the source image's pixels
// (`src_width` x `src_height`), plus a running `clicks` counter so repeated clicks register.
function render({ model, el }) {
  el.classList.add("rfl-clickimage");
  const img = document.createElement("img");
  img.style.imageRendering = "pixelated";
  img.style.cursor = "crosshair";
  img.style.display = "block";
  img.style.maxWidth = "100%";   // never wider than the notebook: shrink rather than scroll
  el.style.maxWidth = "100%";
  const cap = document.createElement("div");
  cap.className = "rfl-clickimage-cap";
  el.append(img, cap);
  let url = null;
  function draw() {
    const data = model.get("png");
    if (url) URL.revokeObjectURL(url);
    url = URL.createObjectURL(new Blob([data && data.buffer ? data.buffer : data], { type: "image/png" }));
    img.src = url;
    img.style.width = `${model.get("display_width")}px`;
    cap.textContent = model.get("caption");
  }
  img.addEventListener("click", (ev) => {
    const r = img.getBoundingClientRect();
    const w = model.get("src_width"), h = model.get("src_height");
    const x = Math.min(w - 1, Math.max(0, Math.floor((ev.clientX - r.left) / r.width * w)));
    const y = Math.min(h - 1, Math.max(0, Math.floor((ev.clientY - r.top) / r.height * h)));
    model.set("clicked", [x, y]);
    model.set("clicks", model.get("clicks") + 1);
    model.save_changes();
  });
  model.on("change:png", draw);
  model.on("change:display_width", draw);
  model.on("change:caption", draw);
  draw();
  return () => {
    if (url) URL.revokeObjectURL(url);
    model.off("change:png", draw);
    model.off("change:display_width", draw);
    model.off("change:caption", draw);
  };
}
export default { render };
