// The campaign view: campaign.json's groups and accidents; a selected accident's analysis
// (.rrd, written by the server on first request) opens in Rerun's web viewer below /rerun/.
"use strict";

function cell(row, text) {
  const td = document.createElement("td");
  td.textContent = text;
  row.appendChild(td);
  return td;
}

function counts(obj) {
  return Object.entries(obj).map(([k, v]) => `${k} ${v}`).join(", ");
}

function pct(x) {
  return x === null || x === undefined ? "n/a" : `${(100 * x).toFixed(1)} %`;
}

function agreement(a) {
  const c = a.confidence;
  return c ? `${c.level} (${c.same}/${c.runs})` : "n/a";
}

// the terminal's "documented root cause" column: yes, no, or empty without a documented type
function documented(d) {
  return d === true ? "yes" : d === false ? "no" : "";
}

function selectAccident(name) {
  for (const tr of document.querySelectorAll("#accidents tr.accident-row")) {
    tr.classList.toggle("selected", tr.dataset.name === name);
  }
  document.getElementById("selected").textContent = `analysis of ${name}`;
  const rrd = `${window.location.origin}/rrd/${encodeURIComponent(name)}.rrd`;
  // notebook=1: the viewer sends no usage analytics (it has no network here, nor needs one)
  document.getElementById("rerun").src = `/rerun/?url=${encodeURIComponent(rrd)}&notebook=1`;
}

function showGroup(id) {
  for (const tr of document.querySelectorAll("#accidents tr.accident-row")) {
    tr.classList.toggle("dimmed", id !== null && tr.dataset.group !== id);
  }
}

function render(c) {
  document.getElementById("summary").textContent =
    `${c.analysed} of ${c.accidents_total} accidents analysed in ${c.groups.length} groups` +
    (c.complete ? "" : `; ${c.failed.length} failed to analyse`);
  const sc = c.scores;
  document.getElementById("scores").textContent = sc
    ? `completeness ${pct(sc.completeness)} (worst type ${pct(sc.worst_completeness)}), ` +
      `purity ${pct(sc.purity)} (worst group ${pct(sc.worst_purity)})`
    : "no accident has a documented type";
  const groups = document.querySelector("#groups tbody");
  for (const g of c.groups) {
    const tr = document.createElement("tr");
    tr.className = "group-row";
    tr.dataset.group = g.id;
    [g.id, g.root_cause, String(g.count), counts(g.agreement), counts(g.types),
      documented(g.documented)].forEach((t) => cell(tr, t));
    tr.addEventListener("click", () => showGroup(g.id));
    groups.appendChild(tr);
  }
  const accidents = document.querySelector("#accidents tbody");
  for (const a of c.accidents) {
    const tr = document.createElement("tr");
    tr.className = "accident-row";
    tr.dataset.name = a.name;
    tr.dataset.group = a.group;
    [a.name, a.group, a.verdict, a.deviating_module || "", agreement(a), a.truth_type || ""].forEach((t) => cell(tr, t));
    tr.addEventListener("click", () => selectAccident(a.name));
    accidents.appendChild(tr);
  }
  const failed = document.getElementById("failed");
  for (const f of c.failed) {
    const p = document.createElement("p");
    p.className = "failed";
    p.textContent = `failed: ${f.name} (${f.source}): ${f.reason}`;
    failed.appendChild(p);
  }
}

fetch("campaign.json")
  .then((r) => {
    if (!r.ok) throw new Error(`campaign.json: HTTP ${r.status}`);
    return r.json();
  })
  .then(render)
  .catch((e) => {
    document.getElementById("summary").textContent = `cannot read the campaign: ${e.message}`;
  });
