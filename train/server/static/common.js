// Shared by every page: API calls, small helpers. The token travels as the login's HttpOnly cookie.
async function api(path, options = {}) {
  const headers = {"Content-Type": "application/json"};
  const r = await fetch(path, Object.assign({headers}, options));
  const body = r.headers.get("content-type")?.includes("json") ? await r.json() : await r.text();
  if (!r.ok) { const e = new Error(typeof body === "string" ? body : JSON.stringify(body.detail)); e.status = r.status; e.body = body; throw e; }
  return body;
}
const esc = (s) => String(s ?? "").replace(/[&<>"]/g, (c) => ({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"}[c]));
const num = (x, d = 3) => x == null ? "-" : (Math.abs(x) >= 1000 ? Math.round(x).toLocaleString("en") : Number(x).toFixed(d));
const dur = (s) => s == null ? "-" : s < 120 ? `${Math.round(s)} s` : s < 7200 ? `${Math.round(s / 60)} min` : `${(s / 3600).toFixed(1)} h`;
function nav(active) {
  const pages = [["/", "Runs"], ["/new", "New experiment"], ["/queue", "Queue"], ["/compare", "Compare"], ["/docs", "API"]];
  document.getElementById("nav").innerHTML = pages.map(([href, name]) =>
    `<a href="${href}" class="${name === active ? "active" : ""}">${name}</a>`).join("");
}
// the training curves every run page and the compare page draw: statistics column -> title
const CURVES = {return_mean: "return", progress_mean: "progress", success_rate: "success", eps: "eps",
                cog_deviation_mean: "COG deviation (m)", pitch_rate_mean: "|pitch rate| (rad/s)", steps_per_s: "steps/s"};
function drawCharts(el, tracesOf, layout = {}, suffix = "") {  // a chart per CURVES figure with traces
  el.innerHTML = "";
  for (const [key, title] of Object.entries(CURVES)) {
    const traces = tracesOf(key);
    if (!traces.some((t) => t.x.length)) continue;  // a figure no row has: no empty chart
    const div = document.createElement("div"); div.className = "chart"; el.appendChild(div);
    Plotly.react(div, traces, Object.assign({title: {text: title + suffix, font: {size: 13}}, height: 260,
      margin: {t: 30, l: 50, r: 10, b: 40}, legend: {font: {size: 9}}}, layout), {displayModeBar: false, responsive: true});
  }
}
function drawCurves(el, series, x) {  // series: [{name, rows}] of statistics rows; x: "step" | "wall_s"
  drawCharts(el, (key) => series.map(({name, rows}) => {
    const pts = rows.filter((r) => r[key] != null && r[x] != null);
    return {x: pts.map((r) => r[x]), y: pts.map((r) => r[key]), name, mode: "lines+markers", type: "scatter"};
  }), {xaxis: {title: {text: x === "step" ? "environment steps" : "wall time (s)"}}, showlegend: series.length > 1});
}
