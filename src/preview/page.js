// page.js — the preview page's script (embedded with page.html): polls status.json, loads the
// current camera's tone-mapped image when a new one is published or a control changes, keeps one
// thumbnail per camera, and offers Stop and downloads. Every URL is relative to the page's
// /TOKEN/ path.
"use strict";
const $ = (id) => document.getElementById(id);
let status = null, shown = -1, pinned = false, serverGone = false;
const loaded = {};      // key of the image last requested for an element id
const thumbVersion = {};

function fmtTime(s) {
  if (s === null || s === undefined || !isFinite(s)) return "–";
  if (s < 60) return s.toFixed(1) + " s";
  const m = Math.floor(s / 60);
  return m + " min " + Math.round(s - 60 * m) + " s";
}
function viewQuery(cam) {
  return "cam=" + cam + "&tmo=" + encodeURIComponent($("tmo").value) + "&ev=" + $("ev").value;
}
// Loads url into the <img> with this id once it differs from what it shows, swapping only when the
// new image is complete (no flicker); then calls done.
function loadInto(id, url, done) {
  if (loaded[id] === url) { if (done) done(); return; }
  loaded[id] = url;
  const img = new Image();
  img.onload = () => { if (loaded[id] === url) { $(id).src = img.src; if (done) done(); } };
  img.src = url;
}
function cameraLine(c) {
  return c.id + " (" + c.imageName + ", " + c.width + "x" + c.height + ", " + c.phase + ")";
}
function updateFigures(c) {
  $("cam").textContent = cameraLine(c);
  $("spp").textContent = c.spp;
  $("relmse").textContent = c.relMse === null ? "–" : c.relMse.toPrecision(4);
  $("elapsed").textContent = fmtTime(c.elapsed);
  let left = fmtTime(c.timeLeft);
  if (c.phase === "done") left = "done";
  else if (left === "–" && c.fraction !== null) left = Math.round(100 * c.fraction) + "% done";
  $("left-time").textContent = left;
  $("throughput").textContent = c.throughput.length === 0 ? "–" :
    c.throughput.map((d) => d.device + ": " + (d.samplesPerSecond / 1e6).toFixed(2) + " M/s").join("; ");
}
function updateMode(c) {
  const mode = $("mode");
  mode.options[1].disabled = mode.options[2].disabled = !c.hasReference;
  if (!c.hasReference && mode.value !== "render") mode.value = "render";
  $("single").hidden = mode.value !== "render";
  $("pair").hidden = mode.value !== "side";
  $("diffbox").hidden = mode.value !== "diff";
}
function drawDiff() {
  const a = $("left"), b = $("right"), cv = $("diff");
  if (!a.naturalWidth || !b.naturalWidth) return;
  if (a.naturalWidth !== b.naturalWidth || a.naturalHeight !== b.naturalHeight) {
    $("diffnote").textContent = "the reference is " + b.naturalWidth + "x" + b.naturalHeight + ", the render " +
      a.naturalWidth + "x" + a.naturalHeight + ": no difference image";
    return;
  }
  const w = a.naturalWidth, h = a.naturalHeight, ctx = cv.getContext("2d");
  cv.width = w; cv.height = h;
  ctx.drawImage(a, 0, 0); const da = ctx.getImageData(0, 0, w, h);
  ctx.drawImage(b, 0, 0); const db = ctx.getImageData(0, 0, w, h);
  for (let i = 0; i < da.data.length; i += 4)
    for (let k = 0; k < 3; ++k) da.data[i + k] = Math.min(255, 4 * Math.abs(da.data[i + k] - db.data[i + k]));
  ctx.putImageData(da, 0, 0);
  $("diffnote").textContent = "";
}
function updateImages(c) {
  if (!c.hasImage) return;
  const url = "image.png?" + viewQuery(shown) + "&v=" + c.version;
  $("dl-png").href = url;
  $("dl-png").download = c.imageName.replace(/\.[^.]*$/, "") + "_preview.png";
  $("dl-exr").href = "image.exr?cam=" + shown + "&v=" + c.version;
  const mode = $("mode").value;
  if (mode === "render") { loadInto("main", url); return; }
  const ref = "reference.png?" + viewQuery(shown);
  loadInto("left", url, mode === "diff" ? drawDiff : null);
  loadInto("right", ref, mode === "diff" ? drawDiff : null);
}
function updateThumbs() {
  const box = $("thumbs");
  status.cameras.forEach((c, i) => {
    let t = $("thumb" + i);
    if (!t) {
      t = document.createElement("div");
      t.id = "thumb" + i; t.className = "thumb";
      t.innerHTML = "<img alt=''><div></div>";
      t.onclick = () => { shown = i; pinned = i !== status.current; refresh(); };
      box.appendChild(t);
    }
    t.classList.toggle("current", i === shown);
    t.classList.toggle("done", c.phase === "done");
    t.lastChild.textContent = "camera " + c.id + ": " + c.phase + (c.spp ? ", " + c.spp + " spp" : "");
    // A rendering camera's thumbnail follows at most every 8th image; a done one shows its final image.
    const last = thumbVersion[i];
    if (c.hasImage && last !== c.version && (last === undefined || c.phase === "done" || c.version - last >= 8)) {
      thumbVersion[i] = c.version;
      t.firstChild.src = "image.png?" + viewQuery(i) + "&thumb=1&v=" + c.version;
    }
  });
}
function refresh() {
  if (!status) return;
  $("stage").textContent = status.stage;
  if (!pinned && status.current >= 0) shown = status.current;
  if (shown < 0 && status.cameras.length) shown = 0;
  const c = status.cameras[shown];
  $("stop").disabled = status.finished;
  updateThumbs();
  if (!c) return;
  updateFigures(c);
  updateMode(c);
  updateImages(c);
}
async function poll() {
  try {
    const r = await fetch("status.json", { cache: "no-store" });
    if (!r.ok) throw new Error("HTTP " + r.status);
    status = await r.json();
    refresh();
    if (serverGone) { serverGone = false; $("msg").textContent = ""; }
  } catch (e) {
    if (status && status.finished) { $("msg").textContent = "clrt has ended; the images shown are its last."; return; }
    serverGone = true;
    $("msg").textContent = "no answer from clrt (" + e.message + "); retrying";
  }
  setTimeout(poll, 250);
}
$("tmo").onchange = refresh;
$("ev").oninput = () => { $("evtext").textContent = $("ev").value; refresh(); };
$("mode").onchange = refresh;
$("stop").onclick = async () => {
  $("stop").disabled = true;
  try { await fetch("stop", { method: "POST" }); $("msg").textContent = "stopping after the current pass…"; }
  catch (e) { $("msg").textContent = "stop failed: " + e.message; }
};
poll();
