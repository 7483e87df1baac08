// `incision tradeoff SCENE`: the speed/accuracy sweep written as CSV, a Pareto markdown table and a PNG plot.
#pragma once

#include <string>

#include "host/app/tradeoff.h"
#include "host/scene/scene.h"

namespace inc::cli {

struct TradeoffCommandOptions {
  TradeoffOptions sweep;
  std::string out_dir = "tradeoff";
  std::string
      models;  // "" = the scene's; else a comma list of "mls", "pbd", "mfs" (haptic local model) switched on instead
  std::string cost = "wall";  // "wall" | "cpu" (sets sweep.cpu_cost; anything else: InputError(--cost))
};

// Writes OUT/tradeoff.csv, OUT/tradeoff.md, OUT/tradeoff.png (through /usr/bin/python3 + matplotlib; a missing
// matplotlib is reported, not fatal). Returns the exit code.
int runTradeoffCommand(const Scene& scene, const TradeoffCommandOptions& options);

}  // namespace inc::cli
