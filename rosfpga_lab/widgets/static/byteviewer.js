// Byte viewer front end (anywidget ESM). Python sends one page of bytes as hex plus the
// fields; this draws the hex + ASCII grid, names the field under the mouse and syncs
// clicks back as `selected` (field index) and `selected_offset` (byte).
function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

function render({ model, el: root }) {
  root.classList.add("rfl-bv");
  const head = el("div", "rfl-bv-head");
  const title = el("b", "rfl-bv-title");
  const prev = el("button", "rfl-bv-prev", "\u25c0");
  const next = el("button", "rfl-bv-next", "\u25b6");
  const pageIn = el("input", "rfl-bv-page");
  pageIn.type = "number";
  pageIn.min = 1;
  const pageOf = el("span", "rfl-bv-pageof");
  head.append(title, " ", prev, " page ", pageIn, pageOf, " ", next);
  const body = el("div", "rfl-bv-body");
  const grid = el("div", "rfl-bv-grid");
  const list = el("div", "rfl-bv-list");
  body.append(grid, list);
  const info = el("div", "rfl-bv-info");
  root.append(head, info, body);

  let owner = [];   // owner[k] = field index of byte page_start + k, or -1
  let cells = [];   // [hexCell, asciiCell] per byte on the page
  let byIndex = new Map(); // field index -> field dict
  let hover = -1;

  function fieldInfo(i) {
    const f = byIndex.get(i);
    return f ? f.info : "";
  }

  function showInfo() {
    const i = hover >= 0 ? hover : model.get("selected");
    const off = model.get("selected_offset");
    if (i >= 0) {
      info.textContent = (hover >= 0 ? "" : "selected: ") + fieldInfo(i);
    } else if (hover < 0 && off >= 0) {
      info.textContent = `byte ${off}: not part of any field`;
    } else {
      info.textContent = "hover or click a byte to name its field";
    }
    info.dataset.field = i;
  }

  function paint() {
    const sel = model.get("selected");
    for (let k = 0; k < cells.length; k++) {
      const on = owner[k] >= 0 && (owner[k] === sel || owner[k] === hover);
      cells[k][0].classList.toggle("hl", on);
      cells[k][1].classList.toggle("hl", on);
      cells[k][0].classList.toggle("sel", owner[k] >= 0 && owner[k] === sel);
    }
    for (const row of list.querySelectorAll("tr[data-i]")) {
      row.classList.toggle("sel", Number(row.dataset.i) === sel);
    }
    showInfo();
  }

  function select(i, off) {
    model.set("selected", i);
    model.set("selected_offset", off);
    model.save_changes();
  }

  function drawGrid() {
    const hex = model.get("page_hex");
    const start = model.get("page_start");
    const rowSize = model.get("row_size");
    const n = hex.length / 2;
    byIndex = new Map();
    for (const f of model.get("fields")) byIndex.set(f.i, f);
    owner = new Array(n).fill(-1);
    const colour = new Map();
    for (const f of model.get("page_fields")) {
      byIndex.set(f.i, f);
      colour.set(f.i, f.colour);
      for (let o = Math.max(f.offset, start); o < Math.min(f.offset + f.size, start + n); o++) {
        owner[o - start] = f.i;
      }
    }
    grid.replaceChildren();
    cells = [];
    for (let r = 0; r < n; r += rowSize) {
      const line = el("div", "rfl-bv-row");
      line.append(el("span", "rfl-bv-off", (start + r).toString(16).padStart(8, "0")));
      const hx = el("span", "rfl-bv-hex");
      const asc = el("span", "rfl-bv-asc");
      for (let k = r; k < Math.min(r + rowSize, n); k++) {
        const v = parseInt(hex.substr(2 * k, 2), 16);
        const h = el("span", "b", hex.substr(2 * k, 2));
        const a = el("span", "a", v >= 32 && v < 127 ? String.fromCharCode(v) : ".");
        for (const c of [h, a]) {
          c.dataset.off = start + k;
          if (owner[k] >= 0) {
            c.style.background = colour.get(owner[k]);
            c.dataset.field = owner[k];
            const f = byIndex.get(owner[k]);
            if (f && f.offset === start + k) c.classList.add("first");
          }
        }
        hx.append(h);
        asc.append(a);
        cells.push([h, a]);
      }
      line.append(hx, asc);
      grid.append(line);
    }
    title.textContent = (model.get("title") ? model.get("title") + " \u2014 " : "") + `${model.get("total")} bytes`;
    pageIn.value = model.get("page") + 1;
    pageIn.max = model.get("n_pages");
    pageOf.textContent = ` of ${model.get("n_pages")} `;
    prev.disabled = model.get("page") <= 0;
    next.disabled = model.get("page") >= model.get("n_pages") - 1;
    paint();
  }

  function drawList() {
    const table = el("table");
    const head = el("tr");
    for (const h of ["", "field", "type", "offset", "size"]) head.append(el("th", "", h));
    table.append(head);
    for (const f of model.get("fields")) {
      const tr = el("tr");
      tr.dataset.i = f.i;
      const sw = el("td", "sw");
      sw.style.background = f.colour;
      tr.append(sw, el("td", "", f.label), el("td", "", f.type), el("td", "", String(f.offset)), el("td", "", String(f.size)));
      tr.title = f.info;
      table.append(tr);
    }
    const more = model.get("fields_truncated");
    list.replaceChildren(table);
    if (more > 0) list.append(el("div", "", `\u2026 ${more} more fields not listed`));
    paint();
  }

  grid.addEventListener("mouseover", (ev) => {
    const t = ev.target.closest("[data-off]");
    hover = t && t.dataset.field !== undefined ? Number(t.dataset.field) : -1;
    paint();
  });
  grid.addEventListener("mouseleave", () => { hover = -1; paint(); });
  grid.addEventListener("click", (ev) => {
    const t = ev.target.closest("[data-off]");
    if (!t) return;
    select(t.dataset.field !== undefined ? Number(t.dataset.field) : -1, Number(t.dataset.off));
  });
  list.addEventListener("click", (ev) => {
    const tr = ev.target.closest("tr[data-i]");
    if (!tr) return;
    const f = byIndex.get(Number(tr.dataset.i));
    select(Number(tr.dataset.i), f ? f.offset : -1);
  });
  prev.addEventListener("click", () => { model.set("page", model.get("page") - 1); model.save_changes(); });
  next.addEventListener("click", () => { model.set("page", model.get("page") + 1); model.save_changes(); });
  pageIn.addEventListener("change", () => {
    const p = Math.max(1, Math.min(Number(pageIn.value) || 1, model.get("n_pages")));
    model.set("page", p - 1);
    model.save_changes();
  });

  const onGrid = () => drawGrid();
  const onList = () => drawList();
  const onSel = () => paint();
  model.on("change:page_hex", onGrid);
  model.on("change:page_fields", onGrid);
  model.on("change:page", onGrid);
  model.on("change:fields", onList);
  model.on("change:selected", onSel);
  model.on("change:selected_offset", onSel);
  drawGrid();
  drawList();
  return () => {
    model.off("change:page_hex", onGrid);
    model.off("change:page_fields", onGrid);
    model.off("change:page", onGrid);
    model.off("change:fields", onList);
    model.off("change:selected", onSel);
    model.off("change:selected_offset", onSel);
  };
}

export default { render };
