// Progress bar / plain progress lines for long commands (run, pack, bench).
#include "base/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>

namespace inc {

Progress::Progress(std::string label, long total, bool quiet, std::FILE* out)
    : label_(std::move(label)),
      total_(total),
      quiet_(quiet),
      tty_(isTerminal(out)),
      out_(out),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

bool Progress::isTerminal(std::FILE* f) { return isatty(fileno(f)) != 0; }

void Progress::update(long done, const std::string& extra) {
  if (quiet_) return;
  const auto now = std::chrono::steady_clock::now();
  if (tty_) {
    // Redraw at most 10 times a second: drawing must not cost the simulation time.
    if (now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
    last_draw_ = now;
    draw(done, extra, false);
  } else {
    // Plain lines at every tenth of the run (or every 5 s when the total is unknown).
    int decile = total_ > 0 ? int(10 * done / total_) : -1;
    bool due = total_ > 0 ? decile != last_decile_ : now - last_draw_ > std::chrono::seconds(5);
    if (!due) return;
    last_decile_ = decile;
    last_draw_ = now;
    draw(done, extra, false);
  }
}

void Progress::finish(const std::string& extra) {
  if (quiet_) return;
  draw(total_ > 0 ? total_ : 0, extra, true);
}

void Progress::draw(long done, const std::string& extra, bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
  char eta[32] = "--";
  if (total_ > 0 && rate > 0) std::snprintf(eta, sizeof eta, "%.1fs", double(total_ - done) / rate);
  if (tty_) {
    const int width = 30;
    const double frac = total_ > 0 ? std::clamp(double(done) / double(total_), 0.0, 1.0) : 0.0;
    const int filled = int(std::round(frac * width));
    std::string bar(std::size_t(filled), '#');
    bar.resize(std::size_t(width), '.');
    std::fprintf(out_, "\r%s [%s] %ld/%ld %.1f steps/s ETA %s %s\033[K", label_.c_str(), bar.c_str(), done, total_,
                 rate, eta, extra.c_str());
    if (final) std::fprintf(out_, "\n");
  } else {
    std::fprintf(out_, "%s: %ld/%ld steps, %.1f steps/s, ETA %s%s%s\n", label_.c_str(), done, total_, rate, eta,
                 extra.empty() ? "" : ", ", extra.c_str());
  }
  std::fflush(out_);
}

}  // namespace inc
