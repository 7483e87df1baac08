// Trajectory files: reading (decimal or C99 hex floats), writing (hex floats for bit-exact replay), checking.
#include "host/io/trajectory.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "model/input_error.h"

namespace inc {

namespace {
bool parseDouble(const std::string& tok, double& out) {
  const char* s = tok.c_str();
  char* end = nullptr;
  out = std::strtod(s, &end);  // accepts decimal and C99 hex floats
  return end != s && *end == '\0';
}
}  // namespace

void validateTrajectory(const Trajectory& trajectory, const std::string& file) {
  if (trajectory.samples.empty()) throw InputError(file, "", "trajectory has no samples");
  for (std::size_t i = 0; i < trajectory.samples.size(); ++i) {
    const DeviceSample& s = trajectory.samples[i];
    const std::string key = "sample " + std::to_string(i);
    const double* q = s.orientation;
    if (!std::isfinite(s.t_s) || !isFinite(s.position_m) || !std::isfinite(q[0]) || !std::isfinite(q[1]) ||
        !std::isfinite(q[2]) || !std::isfinite(q[3]))
      throw InputError(file, key, "non-finite value");
    const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (std::fabs(qn - 1.0) > 1e-3) throw InputError(file, key, "orientation quaternion is not unit length");
    if (i > 0 && !(s.t_s > trajectory.samples[i - 1].t_s))
      throw InputError(file, key, "sample times must strictly increase");
  }
}

Trajectory loadTrajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open trajectory file");
  Trajectory tr;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::vector<std::string> tok;
    for (std::string t; ls >> t;) tok.push_back(t);
    if (tok.empty()) continue;
    const std::string key = "line " + std::to_string(line_no);
    if (tok.size() != 9) throw InputError(path, key, "expected 9 fields: t x y z qw qx qy qz buttons");
    double v[8];
    for (int k = 0; k < 8; ++k)
      if (!parseDouble(tok[k], v[k])) throw InputError(path, key, "not a number: '" + tok[k] + "'");
    char* end = nullptr;
    const unsigned long b = std::strtoul(tok[8].c_str(), &end, 10);
    if (end == tok[8].c_str() || *end != '\0' || b > 0xffffffffUL)
      throw InputError(path, key, "buttons must be an unsigned 32-bit integer");
    DeviceSample s;
    s.t_s = v[0];
    s.position_m = {v[1], v[2], v[3]};
    for (int k = 0; k < 4; ++k) s.orientation[k] = v[4 + k];
    s.buttons = static_cast<std::uint32_t>(b);
    tr.samples.push_back(s);
  }
  validateTrajectory(tr, path);
  return tr;
}

void writeTrajectory(const std::string& path, const Trajectory& trajectory) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw InputError(path, "", "cannot open trajectory file for writing");
  std::fprintf(f, "# t_s x_m y_m z_m qw qx qy qz buttons (hex floats: bit-exact)\n");
  for (const DeviceSample& s : trajectory.samples)
    std::fprintf(f, "%a %a %a %a %a %a %a %a %u\n", s.t_s, s.position_m.x, s.position_m.y, s.position_m.z,
                 s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3], s.buttons);
  const bool ok = std::fclose(f) == 0;
  if (!ok) throw InputError(path, "", "write failed");
}

}  // namespace inc
