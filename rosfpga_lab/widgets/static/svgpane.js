// A clickable SVG (anywidget ESM): Python draws the SVG; elements with data-index are
// clickable and their index is synced back as `selected`.
function render({ model, el }) {
  el.classList.add("rfl-svgpane");
  const holder = document.createElement("div");
  el.append(holder);
  function mark() {
    const sel = model.get("selected");
    for (const g of holder.querySelectorAll("[data-index]")) {
      g.classList.toggle("sel", Number(g.dataset.index) === sel);
    }
  }
  function draw() {
    holder.innerHTML = model.get("svg");
    mark();
  }
  holder.addEventListener("click", (ev) => {
    const g = ev.target.closest("[data-index]");
    if (!g) return;
    model.set("selected", Number(g.dataset.index));
    model.save_changes();
  });
  model.on("change:svg", draw);
  model.on("change:selected", mark);
  draw();
  return () => { model.off("change:svg", draw); model.off("change:selected", mark); };
}
export default { render };
