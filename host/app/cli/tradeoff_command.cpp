// `incision tradeoff`: runs the sweep, writes CSV + markdown, plots error vs ms per frame (log-log) with the budgets.
#include "host/app/cli/tradeoff_command.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "model/input_error.h"

namespace inc::cli {
namespace {

// The plot: one colour per model, one marker per knob, each model's Pareto front drawn as steps, budgets as lines.
const char* kPlotScript = R"PY(
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
src, png, budgets = sys.argv[1], sys.argv[2], [float(b) for b in sys.argv[3].split(",")]
rows = [r for r in csv.DictReader(open(src)) if r["finite"] == "1" and r.get("held", "1") == "1"]
fig, ax = plt.subplots(figsize=(7.5, 5))
series = {}
for r in rows:
    series.setdefault((r["model"], r["knob"]), []).append((float(r["ms_per_frame"]), max(float(r["error"]), 1e-5), r["value"]))
colours = {"mls": "C0", "pbd": "C1", "mfs": "C2"}
markers = {"baseline": "*", "spacing": "o", "support_factor": "<", "safety": "^", "precision": "D", "iterations": "s",
           "substeps": "x", "spheres": "h", "target_spheres": "p", "nodes": "o"}
for key, pts in sorted(series.items()):
    ax.scatter([p[0] for p in pts], [p[1] for p in pts], marker=markers.get(key[1], "v"), color=colours.get(key[0], "C3"),
               s=60 if key[1] == "baseline" else 30, label=f"{key[0]} {key[1]}")
    for p in pts:
        if p[2]:
            ax.annotate(p[2], (p[0], p[1]), fontsize=7, xytext=(3, 3), textcoords="offset points")
for model in sorted({r["model"] for r in rows}):
    pts = sorted((float(r["ms_per_frame"]), max(float(r["error"]), 1e-5)) for r in rows if r["model"] == model)
    front, best = [], float("inf")
    for x, y in pts:
        if y < best:
            front.append((x, y)); best = y
    ax.step([p[0] for p in front], [p[1] for p in front], where="post", alpha=0.5, color=colours.get(model, "C3"),
            label=f"{model} Pareto front")
for b in budgets:
    ax.axvline(b, color="grey", linestyle="--", linewidth=0.8)
    ax.text(b, 0.98, f" {b:g} ms budget", rotation=90, fontsize=8, va="top", transform=ax.get_xaxis_transform())
ax.set_xscale("log"); ax.set_yscale("log")
ax.set_xlabel(sys.argv[5] + " ms per frame (mfs: per haptic tick)"); ax.set_ylabel("relative error vs reference")
ax.set_title(sys.argv[4])
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=7, ncol=2)
fig.tight_layout()
fig.savefig(png, dpi=110)
)PY";

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw InputError(path, "--out", "cannot write the file");
}

}  // namespace

int runTradeoffCommand(const Scene& scene_in, const TradeoffCommandOptions& options) {
  TradeoffCommandOptions o = options;
  if (o.cost != "wall" && o.cost != "cpu") throw InputError("", "--cost", "'" + o.cost + "' is not wall or cpu");
  o.sweep.cpu_cost = o.cost == "cpu";
  Scene scene = scene_in;
  if (!o.models.empty()) {
    scene.models.mls = scene.models.pbd_metaballs = scene.models.haptics = false;
    std::stringstream ss(o.models);
    std::string m;
    while (std::getline(ss, m, ',')) {
      if (m == "mls")
        scene.models.mls = true;
      else if (m == "pbd")
        scene.models.pbd_metaballs = true;
      else if (m == "mfs")
        scene.models.haptics = true;
      else
        throw InputError("", "--models", "unknown model '" + m + "' (mls, pbd, mfs)");
    }
  }
  const TradeoffResult r = runTradeoff(scene, o.sweep);
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec) throw InputError(o.out_dir, "--out", "cannot create the folder: " + ec.message());
  const std::string csv = o.out_dir + "/tradeoff.csv", md = o.out_dir + "/tradeoff.md",
                    py = o.out_dir + "/plot_tradeoff.py", png = o.out_dir + "/tradeoff.png";
  writeFile(csv, tradeoffCsv(r));
  const std::string report = tradeoffMarkdown(r, o.sweep.budgets_ms);
  writeFile(md, report);
  writeFile(py, kPlotScript);
  std::string budgets;
  for (double b : o.sweep.budgets_ms) budgets += (budgets.empty() ? "" : ",") + std::to_string(b);
  std::string title = scene.name;
  for (char& c : title)
    if (c == '\'' || c == '\\') c = ' ';
  const std::string cmd = "/usr/bin/python3 '" + py + "' '" + csv + "' '" + png + "' '" + budgets + "' '" + title +
                          " (" + r.backend + "): error vs cost' '" + r.cost + "' 2>&1";
  const int rc = std::system(cmd.c_str());
  std::fputs(report.c_str(), stdout);
  std::printf("tradeoff: %s: %zu settings, %s, %s%s\n", scene.name.c_str(), r.rows.size(), csv.c_str(), md.c_str(),
              rc == 0 ? (", " + png).c_str() : " (no plot: /usr/bin/python3 with matplotlib is needed)");
  return 0;
}

}  // namespace inc::cli
