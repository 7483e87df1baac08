// Terminal progress: a redrawn bar with steps/s and ETA on a TTY, plain periodic lines otherwise.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace inc {

class Progress {
 public:
  // total == 0 means unknown (no ETA). quiet suppresses everything.
  Progress(std::string label, long total, bool quiet = false, std::FILE* out = stderr);
  void update(long done, const std::string& extra = "");
  void finish(const std::string& extra = "");
  static bool isTerminal(std::FILE* f);

 private:
  void draw(long done, const std::string& extra, bool final);
  std::string label_;
  long total_;
  bool quiet_, tty_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_decile_ = -1;
};

}  // namespace inc
