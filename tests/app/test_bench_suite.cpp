// The scaling suite (tools/bench-suite) runs end to end in --quick mode on the CPU: merged CSV, table and plots.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>
#include "test_paths.h"
#include "tests/support/repo_paths.h"

namespace fs = std::filesystem;

TEST(BenchSuite, QuickCpuRunProducesMergedCsvTableAndPlots) {
  const std::string bin = INCISION_BINARY_DIR, src = inc::test::sourceDir();
  for (const char* b : {"bench_neighbors", "bench_mls", "bench_pbd", "bench_scaling"})
    if (!fs::exists(fs::path(bin) / b)) GTEST_SKIP() << b << " not built (cmake --build build builds it)";
  // One folder per process: two checkouts running their suites at once must not share it.
  const fs::path out = fs::temp_directory_path() / ("incision_bench_suite_quick_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string cmd = "OMP_NUM_THREADS=2 bash '" + src + "/tools/bench-suite' --quick --cpu-only --build '" + bin +
                          "' --out '" + out.string() + "' > '" + out.string() + ".log' 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream log(out.string() + ".log");
  std::stringstream ss;
  ss << log.rdbuf();
  ASSERT_EQ(rc, 0) << ss.str();
  // Every suite contributed rows for both precisions.
  std::ifstream csv(out / "suite.csv");
  ASSERT_TRUE(csv) << ss.str();
  std::string line, all;
  std::getline(csv, line);
  EXPECT_EQ(line, "suite,backend,precision,n,ms,ms_min,ms_max,items_per_s,gbytes_per_s,host_peak_mib,device_peak_mib");
  int frame_rows = 0;
  while (std::getline(csv, line)) {
    all += line + "\n";
    // Whole-frame rows carry their spread (min <= median <= max), the compulsory-traffic bandwidth and the row's
    // peak host memory (positive; the process alone holds more than 1 MiB), and no device memory on the CPU.
    if (line.rfind("frame_default_scene,", 0) == 0) {
      std::vector<std::string> f;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) f.push_back(c);
      ASSERT_EQ(f.size(), 11u) << line;
      EXPECT_LE(std::stod(f[5]), std::stod(f[4])) << "min <= median: " << line;
      EXPECT_GE(std::stod(f[6]), std::stod(f[4])) << "max >= median: " << line;
      EXPECT_GT(std::stod(f[8]), 0.0) << "GB/s: " << line;
      EXPECT_GT(std::stod(f[9]), 1.0) << "host peak MiB: " << line;
      EXPECT_EQ(std::stod(f[10]), 0.0) << "device peak MiB on the CPU: " << line;
      ++frame_rows;
    }
  }
  EXPECT_GE(frame_rows, 2);
  // Every row of every suite carries its spread and the row's peak host memory (issue 10: median and spread,
  // peak memory per row), and on the CPU no device memory.
  std::stringstream rows_in(all);
  int checked = 0;
  for (std::string row; std::getline(rows_in, row);) {
    std::vector<std::string> f;
    std::stringstream ls(row);
    for (std::string c; std::getline(ls, c, ',');) f.push_back(c);
    ASSERT_EQ(f.size(), 11u) << row;
    ASSERT_FALSE(f[5].empty() || f[6].empty()) << "no spread: " << row;
    EXPECT_LE(std::stod(f[5]), std::stod(f[4]) * (1 + 1e-9)) << row;
    EXPECT_GE(std::stod(f[6]), std::stod(f[4]) * (1 - 1e-9)) << row;
    ASSERT_FALSE(f[9].empty()) << "no host peak: " << row;
    EXPECT_GT(std::stod(f[9]), 1.0) << row;
    ++checked;
  }
  EXPECT_GT(checked, 10);
  for (const char* s :
       {"neighbor_search,cpu,float32", "neighbor_search,cpu,float64", "mls_step,cpu,float32", "mls_step,cpu,float64",
        "pbd_iteration_jacobi,cpu,float32", "pbd_iteration_jacobi,cpu,float64",
        "pbd_iteration_gauss_seidel,cpu,float32", "pbd_iteration_gauss_seidel,cpu,float64", "skinning,cpu,float32",
        "skinning,cpu,float64", "frame_default_scene,cpu,float32", "frame_default_scene,cpu,float64"})
    EXPECT_NE(all.find(s), std::string::npos) << "missing rows " << s << "\n" << all;
  EXPECT_TRUE(fs::exists(out / "suite.md"));
  if (std::system("/usr/bin/python3 -c 'import matplotlib' > /dev/null 2>&1") == 0) {
    for (const char* p : {"neighbor_search.png", "mls_step.png", "pbd_iteration_jacobi.png",
                          "pbd_iteration_gauss_seidel.png", "skinning.png", "frame_default_scene.png"}) {
      EXPECT_TRUE(fs::exists(out / p)) << p;
    }
  }
  fs::remove_all(out);
}
