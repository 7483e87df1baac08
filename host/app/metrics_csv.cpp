// Writes one CSV row per frame so users can plot cost and energy against time in any tool.
#include "host/app/metrics_csv.h"

#include <iomanip>

#include "model/input_error.h"

namespace inc {

MetricsCsv::MetricsCsv(const std::string& path) : path_(path), out_(path) {
  if (!out_) throw InputError(path, "", "cannot create the metrics file");
  out_ << std::setprecision(9);
}

void MetricsCsv::write(long frame, double time_s, double wall_ms, const FrameReport& r) {
  if (!header_written_) {
    for (const auto& s : r.stages) stages_.push_back(s.stage);
    for (const auto& c : r.counters) counters_.push_back(c.first);
    out_ << "frame,time_s,wall_ms,substeps,dt_s";
    for (const auto& s : stages_) out_ << ",ms_" << s;
    out_ << ",kinetic_J,elastic_J,potential_J,total_J,max_displacement_m,finite";
    for (const auto& c : counters_) out_ << "," << c;
    out_ << "\n";
    header_written_ = true;
  }
  out_ << frame << ',' << time_s << ',' << wall_ms << ',' << r.substeps << ',' << r.dt;
  for (const auto& name : stages_) {
    double ms = 0.0;
    for (const auto& s : r.stages)
      if (s.stage == name) ms = s.ms;
    out_ << ',' << ms;
  }
  const double total = r.kinetic_energy + r.elastic_energy + r.potential_energy;
  out_ << ',' << r.kinetic_energy << ',' << r.elastic_energy << ',' << r.potential_energy << ',' << total << ','
       << r.max_displacement << ',' << (r.finite ? 1 : 0);
  for (const auto& name : counters_) {
    auto it = r.counters.find(name);
    out_ << ',' << (it == r.counters.end() ? 0.0 : it->second);
  }
  out_ << '\n';
  out_.flush();  // a crash or kill must not lose the rows already computed
}

}  // namespace inc
