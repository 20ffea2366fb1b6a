#include "timeopt/viz/plan_page.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "timeopt/core/files.h"

namespace timeopt {
namespace {

// Debian's copies (libjs-three r111 with its UMD OrbitControls, libjs-chart.js 3.9).
constexpr const char* kThreeJs = "/usr/share/javascript/three/three.min.js";
constexpr const char* kOrbitControlsJs = "/usr/share/javascript/three/examples/js/controls/OrbitControls.js";
constexpr const char* kChartJs = "/usr/share/javascript/chart.js/chart.min.js";

std::string Library(const char* path, const char* package) {
  std::string text;
  try {
    text = ReadTextFile(path);
  } catch (const FileError&) {
    throw FileError(std::string("the 3D page inlines ") + path + ": install Debian's " + package +
                    " (scripts/install_deps.sh main)");
  }
  // Inside <script>, a "</script" would end the element.
  for (size_t at = text.find("</script"); at != std::string::npos; at = text.find("</script", at))
    text.replace(at, 2, "<\\/");
  return text;
}

// A JSON string literal safe inside <script> (no "</", no control characters).
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '<':
        out += "\\u003c";
        break;
      case '\n':
        out += "\\n";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

void Number(std::string* out, double value, const char* format = "%.6g") {
  char buffer[32];
  if (!std::isfinite(value)) {
    *out += "null";
    return;
  }
  std::snprintf(buffer, sizeof(buffer), format, value);
  *out += buffer;
}

// "[a,b,c]" of a vector, "null" for infinite entries (no limit).
std::string Triple(const Eigen::Vector3d& v) {
  std::string out = "[";
  for (int a = 0; a < 3; ++a) {
    if (a > 0) out += ",";
    Number(&out, v(a));
  }
  return out + "]";
}

// The page's code and layout (our own). DATA is defined before it.
constexpr const char* kStyle = R"CSS(
html, body { margin: 0; height: 100%; font-family: sans-serif; font-size: 13px; color: #222; }
body { display: flex; }
#view { flex: 1 1 62%; position: relative; min-width: 300px; }
#panel { flex: 0 0 38%; max-width: 560px; overflow-y: auto; padding: 8px 12px; box-sizing: border-box;
         border-left: 1px solid #ccc; background: #fafafa; }
h1 { font-size: 16px; margin: 4px 0 8px; }
table { border-collapse: collapse; margin-bottom: 8px; }
td { padding: 1px 8px 1px 0; vertical-align: top; }
td:first-child { color: #666; white-space: nowrap; }
#colorbar { position: absolute; left: 12px; bottom: 12px; background: rgba(255,255,255,0.85); padding: 4px 8px;
            border-radius: 4px; }
#colorbar .bar { width: 180px; height: 10px; margin: 3px 0;
                 background: linear-gradient(to right, rgb(30,60,230), rgb(40,200,120), rgb(250,220,30), rgb(230,40,30)); }
#colorbar .ends { display: flex; justify-content: space-between; width: 180px; }
#controls { display: flex; align-items: center; gap: 8px; margin: 6px 0 10px; }
#time { flex: 1; }
.chart { height: 170px; margin-bottom: 6px; }
)CSS";

constexpr const char* kApp = R"JS(
(function () {
  'use strict';
  var S = DATA.samples, N = S.t.length, T = S.t[N - 1];
  // Colour of a speed share in [0, 1]: blue, green, yellow, red.
  function colour(share) {
    var stops = [[30, 60, 230], [40, 200, 120], [250, 220, 30], [230, 40, 30]];
    var x = Math.min(Math.max(share, 0), 1) * (stops.length - 1), i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
    return stops[i].map(function (c, k) { return (c + f * (stops[i + 1][k] - c)) / 255; });
  }
  var speed = [], top = 0;
  for (var i = 0; i < N; ++i) {
    var s = Math.hypot(S.v[3 * i], S.v[3 * i + 1], S.v[3 * i + 2]);
    speed.push(s);
    top = Math.max(top, s);
  }
  var scale = top > 0 ? top : 1;

  // ---- the 3D view ----
  var view = document.getElementById('view');
  var renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xf4f6f8);
  view.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  var sun = new THREE.DirectionalLight(0xffffff, 0.6);
  sun.position.set(0.4, -0.6, 1.0);
  scene.add(sun);
  var box = new THREE.Box3();
  var path = new Float32Array(3 * N), colours = new Float32Array(3 * N);
  for (var i = 0; i < N; ++i) {
    path[3 * i] = S.p[3 * i]; path[3 * i + 1] = S.p[3 * i + 1]; path[3 * i + 2] = S.p[3 * i + 2];
    var c = colour(speed[i] / scale);
    colours[3 * i] = c[0]; colours[3 * i + 1] = c[1]; colours[3 * i + 2] = c[2];
    box.expandByPoint(new THREE.Vector3(S.p[3 * i], S.p[3 * i + 1], S.p[3 * i + 2]));
  }
  var size = box.getSize(new THREE.Vector3()), diag = Math.max(size.length(), 1e-3), centre = box.getCenter(new THREE.Vector3());
  var line = new THREE.BufferGeometry();
  line.setAttribute('position', new THREE.BufferAttribute(path, 3));
  line.setAttribute('color', new THREE.BufferAttribute(colours, 3));
  scene.add(new THREE.Line(line, new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors, linewidth: 2})));
  // Voxels: one instanced box each.
  var V = DATA.voxels;
  if (V && V.count > 0) {
    var cube = new THREE.BoxBufferGeometry(V.size, V.size, V.size);
    var mesh = new THREE.InstancedMesh(cube, new THREE.MeshLambertMaterial({color: 0x8a8f98, transparent: true, opacity: 0.55}), V.count);
    var m = new THREE.Matrix4();
    for (var i = 0; i < V.count; ++i) {
      m.makeTranslation((V.index[3 * i] + 0.5) * V.size, (V.index[3 * i + 1] + 0.5) * V.size, (V.index[3 * i + 2] + 0.5) * V.size);
      mesh.setMatrixAt(i, m);
    }
    mesh.instanceMatrix.needsUpdate = true;
    mesh.frustumCulled = false;  // (its bounds are the one box's, at the origin)
    scene.add(mesh);
  }
  // A ground grid under everything, 1 m cells where that gives at most 200 lines.
  var ground = box.clone();
  if (V && V.count > 0) {
    for (var i = 0; i < V.count; ++i) ground.expandByPoint(new THREE.Vector3((V.index[3 * i] + 0.5) * V.size, (V.index[3 * i + 1] + 0.5) * V.size, (V.index[3 * i + 2] + 0.5) * V.size));
  }
  var extent = Math.max(ground.max.x - ground.min.x, ground.max.y - ground.min.y, 1e-3);
  // Cells of 1, 2 or 5 times a power of ten, 10 to 25 across.
  var raw = extent / 12, power = Math.pow(10, Math.floor(Math.log10(raw)));
  var cell = raw / power < 2 ? power : raw / power < 5 ? 2 * power : 5 * power;
  var lines = Math.ceil(extent / cell) + 2, grid = new THREE.GridHelper(lines * cell, lines, 0xb0b5bc, 0xd5d9de);
  grid.rotation.x = Math.PI / 2;
  grid.position.set((ground.min.x + ground.max.x) / 2, (ground.min.y + ground.max.y) / 2, Math.min(ground.min.z, box.min.z) - 0.5 * (V ? V.size : 0));
  scene.add(grid);
  var radius = 0.007 * diag;
  function ball(where, colour, r) {
    var b = new THREE.Mesh(new THREE.SphereBufferGeometry(r, 20, 14), new THREE.MeshLambertMaterial({color: colour}));
    b.position.set(where[0], where[1], where[2]);
    scene.add(b);
    return b;
  }
  ball(DATA.start, 0x1a9e3a, 1.6 * radius);
  ball(DATA.goal, 0xc62828, 1.6 * radius);
  var vehicle = ball(DATA.start, 0x202020, 1.2 * radius);
  var camera = new THREE.PerspectiveCamera(45, 1, diag * 1e-3, diag * 50);
  camera.up.set(0, 0, 1);
  camera.position.set(centre.x - 0.55 * diag, centre.y - 0.85 * diag, centre.z + 0.65 * diag);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();
  function resize() {
    var w = view.clientWidth || 640, h = view.clientHeight || 480;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();
  document.getElementById('vmin').textContent = '0';
  document.getElementById('vmax').textContent = top.toFixed(2);

  // ---- summary ----
  document.getElementById('title').textContent = DATA.title;
  var table = document.getElementById('summary');
  DATA.summary.forEach(function (row) {
    var tr = document.createElement('tr');
    row.forEach(function (text) { var td = document.createElement('td'); td.textContent = text; tr.appendChild(td); });
    table.appendChild(tr);
  });

  // ---- plots ----
  var now = 0;
  var cursor = {id: 'cursor', afterDraw: function (chart) {
    var x = chart.scales.x.getPixelForValue(now), a = chart.chartArea, g = chart.ctx;
    g.save(); g.strokeStyle = '#333'; g.lineWidth = 1; g.beginPath(); g.moveTo(x, a.top); g.lineTo(x, a.bottom); g.stroke(); g.restore();
  }};
  var axisColours = ['#d62728', '#2ca02c', '#1f77b4'];
  function series(values, k) { var out = []; for (var i = 0; i < N; ++i) out.push({x: S.t[i], y: values(i, k)}); return out; }
  function level(y) { return [{x: 0, y: y}, {x: T, y: y}]; }
  function plot(id, label, values, limit, withSpeed) {
    var sets = [];
    if (withSpeed) sets.push({label: 'speed', data: series(function (i) { return speed[i]; }), borderColor: '#000', borderWidth: 1.5});
    ['x', 'y', 'z'].forEach(function (name, k) {
      sets.push({label: name, data: series(values, k), borderColor: axisColours[k], borderWidth: 1});
    });
    var seen = {};
    (limit || []).forEach(function (l, k) {
      if (l === null || seen[l]) return;
      seen[l] = true;
      var name = 'per-axis limit' + (limit[0] === limit[1] && limit[1] === limit[2] ? '' : ' ' + ['x', 'y', 'z'][k]);
      sets.push({label: name, data: level(l), borderColor: '#888', borderDash: [5, 4], borderWidth: 1});
      if (!withSpeed) sets.push({label: '', data: level(-l), borderColor: '#888', borderDash: [5, 4], borderWidth: 1});
    });
    return new Chart(document.getElementById(id), {
      type: 'line', data: {datasets: sets}, plugins: [cursor],
      options: {animation: false, parsing: false, normalized: true, responsive: true, maintainAspectRatio: false,
                elements: {point: {radius: 0}}, events: [],
                plugins: {legend: {labels: {boxWidth: 12, filter: function (item) { return item.text !== ''; }}},
                          title: {display: true, text: label}},
                scales: {x: {type: 'linear', min: 0, max: T, title: {display: true, text: 't, s'}}}}
    });
  }
  var charts = [
    plot('speed', 'speed and velocity, m/s', function (i, k) { return S.v[3 * i + k]; }, DATA.limits.velocity, true),
    plot('acc', 'acceleration, m/s²', function (i, k) { return S.a[3 * i + k]; }, DATA.limits.acceleration, false),
    plot('jerk', 'jerk, m/s³', function (i, k) { return S.j[3 * i + k]; }, DATA.limits.jerk, false)
  ];

  // ---- time ----
  var slider = document.getElementById('time'), label = document.getElementById('tlabel'), button = document.getElementById('play');
  var playing = false, last = null;
  function show(t) {
    now = Math.min(Math.max(t, 0), T);
    var lo = 0, hi = N - 1;
    while (hi - lo > 1) { var mid = (lo + hi) >> 1; if (S.t[mid] <= now) lo = mid; else hi = mid; }
    var f = S.t[hi] > S.t[lo] ? (now - S.t[lo]) / (S.t[hi] - S.t[lo]) : 0;
    vehicle.position.set(S.p[3 * lo] + f * (S.p[3 * hi] - S.p[3 * lo]), S.p[3 * lo + 1] + f * (S.p[3 * hi + 1] - S.p[3 * lo + 1]),
                         S.p[3 * lo + 2] + f * (S.p[3 * hi + 2] - S.p[3 * lo + 2]));
    slider.value = String(Math.round(1000 * now / T));
    label.textContent = now.toFixed(2) + ' / ' + T.toFixed(2) + ' s, ' + (speed[lo] + f * (speed[hi] - speed[lo])).toFixed(2) + ' m/s';
    charts.forEach(function (c) { c.draw(); });
  }
  slider.addEventListener('input', function () { playing = false; button.textContent = 'Play'; show(T * slider.value / 1000); });
  button.addEventListener('click', function () {
    if (!playing && now >= T) show(0);
    playing = !playing;
    last = null;
    button.textContent = playing ? 'Pause' : 'Play';
  });
  function frame(stamp) {
    if (playing) {
      if (last !== null) show(now + (stamp - last) / 1000);
      last = stamp;
      if (now >= T) { playing = false; button.textContent = 'Play'; }
    }
    controls.update();
    renderer.render(scene, camera);
    requestAnimationFrame(frame);
  }
  show(0);
  renderer.render(scene, camera);
  document.body.setAttribute('data-samples', String(N));
  document.body.setAttribute('data-ready', 'true');
  requestAnimationFrame(frame);
})();
)JS";

constexpr const char* kBody = R"HTML(<body data-ready="false" data-samples="0">
<div id="view"><div id="colorbar">speed, m/s<div class="bar"></div><div class="ends"><span id="vmin"></span><span id="vmax"></span></div></div></div>
<div id="panel">
<h1 id="title"></h1>
<table id="summary"></table>
<div id="controls"><button id="play">Play</button><input type="range" id="time" min="0" max="1000" value="0"><span id="tlabel"></span></div>
<div class="chart"><canvas id="speed"></canvas></div>
<div class="chart"><canvas id="acc"></canvas></div>
<div class="chart"><canvas id="jerk"></canvas></div>
</div>
)HTML";

}  // namespace

std::string PlanPageHtml(const Trajectory& trajectory, const VehicleLimits& limits, const OccupancyMap* map,
                         const PlanPageOptions& options) {
  if (!(options.sample_rate_hz > 0.0) || !std::isfinite(options.sample_rate_hz) || options.max_samples < 2) {
    throw std::invalid_argument("3D page: sample_rate_hz must be a positive number and max_samples at least 2");
  }
  const std::string three = Library(kThreeJs, "libjs-three");
  const std::string orbit = Library(kOrbitControlsJs, "libjs-three");
  const std::string chart = Library(kChartJs, "libjs-chart.js");
  // Samples: the rate, or fewer over a long flight.
  const double T = trajectory.duration();
  const double rate = std::min(options.sample_rate_hz, (options.max_samples - 1) / std::max(T, 1e-300));
  const std::vector<TrajectoryState> samples = trajectory.Sample(rate);
  std::string data = "const DATA = {\"title\": " + Quoted(options.title) + ", \"samples\": {";
  // "name": [...] of one number per sample (the times) or three (a vector, x y z per sample).
  const auto column = [&](const char* name, const std::vector<double>& values, const char* format) {
    data += std::string("\"") + name + "\": [";
    for (size_t i = 0; i < values.size(); ++i) {
      if (i > 0) data += ",";
      Number(&data, values[i], format);
    }
    data += "]";
  };
  std::vector<double> t, p, v, a, j;
  for (const TrajectoryState& s : samples) {
    t.push_back(s.t);
    for (int k = 0; k < 3; ++k) {
      p.push_back(s.position(k));
      v.push_back(s.velocity(k));
      a.push_back(s.acceleration(k));
      j.push_back(s.jerk(k));
    }
  }
  column("t", t, "%.9g");
  data += ", ";
  column("p", p, "%.7g");
  data += ", ";
  column("v", v, "%.5g");
  data += ", ";
  column("a", a, "%.5g");
  data += ", ";
  column("j", j, "%.5g");
  data += "}, ";
  const Eigen::Vector3d start = samples.front().position, goal = samples.back().position;
  data += "\"start\": " + Triple(start) + ", \"goal\": " + Triple(goal) + ", ";
  const Eigen::Vector3d none = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  data += "\"limits\": {\"velocity\": " + Triple(limits.max_velocity) +
          ", \"acceleration\": " + Triple(limits.max_acceleration) +
          ", \"jerk\": " + Triple(limits.max_jerk ? *limits.max_jerk : none) + "}, ";
  std::vector<std::pair<std::string, std::string>> summary = options.summary;
  data += "\"voxels\": ";
  if (map == nullptr) {
    data += "null";
  } else {
    std::vector<Eigen::Vector3d> path;
    for (const TrajectoryState& s : samples) path.push_back(s.position);
    // The voxels near the path, thinned evenly to max_voxels.
    const std::vector<Eigen::Vector3d> all =
        OccupiedVoxelsNear(*map, path, options.voxel_radius, 4 * options.max_voxels);
    const size_t stride =
        std::max<size_t>(1, (all.size() + options.max_voxels - 1) / std::max<size_t>(options.max_voxels, 1));
    const double res = map->resolution();
    size_t count = 0;
    std::string index;
    for (size_t i = 0; i < all.size(); i += stride, ++count) {
      for (int a = 0; a < 3; ++a) {
        if (!index.empty()) index += ",";
        index += std::to_string(static_cast<long>(std::floor(all[i](a) / res)));
      }
    }
    data += "{\"size\": ";
    Number(&data, res, "%.9g");
    data += ", \"count\": " + std::to_string(count) + ", \"index\": [" + index + "]}";
    char radius[32];
    std::snprintf(radius, sizeof(radius), "%.3g", options.voxel_radius);
    summary.emplace_back(
        "voxels",
        std::to_string(count) + " occupied within " + radius + " m of the path" +
            (stride > 1 ? " (every " + std::to_string(stride) + "th of " + std::to_string(all.size()) + ")" : ""));
  }
  data += ", \"summary\": [";
  for (size_t i = 0; i < summary.size(); ++i) {
    data += (i ? ", [" : "[") + Quoted(summary[i].first) + ", " + Quoted(summary[i].second) + "]";
  }
  data += "]};";
  std::string page = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>";
  for (const char c : options.title)
    page += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
  page += "</title>\n<style>" + std::string(kStyle) + "</style>\n";
  page += "<script>" + three + "</script>\n<script>" + orbit + "</script>\n<script>" + chart + "</script>\n</head>\n";
  page += kBody;
  page += "<script>" + data + "</script>\n<script>" + std::string(kApp) + "</script>\n</body></html>\n";
  if (page.size() > kMaxPlanPageBytes)
    throw std::logic_error("3D page: " + std::to_string(page.size()) + " bytes, above the cap");
  return page;
}

void WritePlanPageHtml(const Trajectory& trajectory, const VehicleLimits& limits, const OccupancyMap* map,
                       const std::string& path, const PlanPageOptions& options) {
  WriteTextFile(path, PlanPageHtml(trajectory, limits, map, options));
}

}  // namespace timeopt
