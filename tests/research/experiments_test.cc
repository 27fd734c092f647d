// SPDX-License-Identifier: Apache-2.0
#include "rigcal/research/experiments.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace rigcal {
namespace {

research::ExperimentOptions Small(int samples) {
  research::ExperimentOptions options;
  options.samples = samples;
  options.seed = 7;
  options.threads = 2;
  options.crb_samples = 40;
  return options;
}

const research::ExperimentRow& Row(const research::ExperimentResult& r, const std::string& series, double eps,
                         int num_poses = 0, double swept = research::kNotAvailable) {
  for (const research::ExperimentRow& row : r.rows) {
    if (row.series != series || std::abs(row.eps_deg - eps) > 1e-9) continue;
    if (num_poses > 0 && row.num_poses != num_poses) continue;
    if (std::isfinite(swept) && !(std::abs(row.alpha_max_deg - swept) < 1e-9 ||
                                  std::abs(row.max_scale_error_pct - swept) < 1e-9)) {
      continue;
    }
    return row;
  }
  ADD_FAILURE() << "no row " << series << " eps " << eps << " K " << num_poses << " swept "
                << swept;
  static const research::ExperimentRow kEmpty;
  return kEmpty;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

int Fields(const std::string& line) {
  return 1 + static_cast<int>(std::count(line.begin(), line.end(), ','));
}

int Count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t pos = text.find(needle); pos != std::string::npos;
       pos = text.find(needle, pos + needle.size())) {
    ++n;
  }
  return n;
}

std::string ReadFile(const std::string& path) {
  std::ifstream file(path);
  std::stringstream content;
  content << file.rdbuf();
  return content.str();
}

TEST(ExperimentsTest, GridsNamesAndOptionChecks) {
  const std::vector<double> grid = research::LinearGrid(0.0, 3.0, 0.1);
  ASSERT_EQ(grid.size(), 31u);
  EXPECT_EQ(grid[3], 0.3);
  EXPECT_EQ(grid.back(), 3.0);
  EXPECT_EQ(research::LinearGrid(0.0, 100.0, 5.0).size(), 21u);
  for (research::ExperimentKind kind : {research::ExperimentKind::kStability, research::ExperimentKind::kPoses,
                              research::ExperimentKind::kMotionModel, research::ExperimentKind::kScaleModel}) {
    research::ExperimentKind parsed = research::ExperimentKind::kStability;
    ASSERT_TRUE(research::ParseExperimentKind(ToString(kind), &parsed));
    EXPECT_EQ(parsed, kind);
  }
  research::ExperimentKind unchanged = research::ExperimentKind::kPoses;
  EXPECT_FALSE(research::ParseExperimentKind("stabilty", &unchanged));
  EXPECT_EQ(unchanged, research::ExperimentKind::kPoses);

  EXPECT_TRUE(research::ExperimentOptions().Check().ok()) << research::ExperimentOptions().Check().message();
  research::ExperimentOptions bad;
  bad.samples = 0;
  EXPECT_FALSE(bad.Check().ok());
  EXPECT_EQ(bad.Check().message().rfind("samples: ", 0), 0u) << bad.Check().message();
  bad = research::ExperimentOptions();
  bad.alpha_max_deg = {};
  EXPECT_FALSE(bad.Check().ok());
  EXPECT_EQ(bad.Check().message().rfind("alpha_max_deg: ", 0), 0u) << bad.Check().message();
  bad = research::ExperimentOptions();
  bad.poses_max = 3;
  EXPECT_FALSE(bad.Check().ok());
  EXPECT_EQ(bad.Check().message().rfind("poses_max: ", 0), 0u) << bad.Check().message();
  const research::ExperimentResult result = research::RunStability(bad);
  EXPECT_FALSE(result.error.empty());
  EXPECT_TRUE(result.rows.empty());
}

// Thesis 5.1.2: without noise both methods are exact; with noise the error grows linearly with
// eps. Medians are compared: to first order the estimate is a linear function of the pose noise,
// so every quantile of the error doubles from 1 to 2 deg. With 400 independent samples per point
// the sampling error of a median is below about 10 %, so a ratio outside [1.4, 2.8] is not
// chance. (Means are not used: the rare gross failures near 180 deg rotations dominate the mean
// of a few hundred samples.)
TEST(ExperimentsTest, StabilityExactWithoutNoiseAndLinearInNoise) {
  research::ExperimentOptions options = Small(400);
  options.stability_eps_deg = {0.0, 1.0, 2.0};
  const research::ExperimentResult r = research::RunStability(options);
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_EQ(r.rows.size(), 6u);
  for (const char* series : {"lls", "nl"}) {
    const research::ErrorStats& zero = Row(r, series, 0.0).errors;
    EXPECT_EQ(zero.failed, 0);
    EXPECT_EQ(zero.usable, 400);
    for (double v : {zero.rot_mean_deg, zero.dir_mean_deg, zero.dist_mean_pct, zero.scale_mean_pct,
                     zero.rot_rms_deg}) {
      EXPECT_LT(v, 1e-6) << series;
    }
    const research::ErrorStats& one = Row(r, series, 1.0).errors;
    const research::ErrorStats& two = Row(r, series, 2.0).errors;
    for (auto [a, b] :
         std::vector<std::pair<double, double>>{{one.rot_median_deg, two.rot_median_deg},
                                                {one.dir_median_deg, two.dir_median_deg},
                                                {one.dist_median_pct, two.dist_median_pct},
                                                {one.scale_median_pct, two.scale_median_pct}}) {
      ASSERT_GT(a, 0.0) << series;
      EXPECT_GT(b / a, 1.4) << series << " " << a << " -> " << b;
      EXPECT_LT(b / a, 2.8) << series << " " << a << " -> " << b;
    }
    // The bound column is linear in eps by construction and zero without noise.
    EXPECT_EQ(Row(r, series, 0.0).crb.rot_deg, 0.0);
    EXPECT_NEAR(Row(r, series, 2.0).crb.rot_deg, 2.0 * Row(r, series, 1.0).crb.rot_deg, 1e-12);
    // The bound bounds the RMS error (0.8: margin for the sampling error of 40 geometries).
    EXPECT_GE(one.rot_rms_deg, 0.8 * Row(r, series, 1.0).crb.rot_deg) << series;
    EXPECT_GE(one.dir_rms_deg, 0.8 * Row(r, series, 1.0).crb.dir_deg) << series;
  }
}

// Thesis 5.1.2: "The combined non-linear estimation method yields better results for position".
// LLS and NL see the same samples, so the comparison is paired.
TEST(ExperimentsTest, NonlinearPositionNotWorseThanLinear) {
  research::ExperimentOptions options = Small(400);
  options.stability_eps_deg = {1.0};
  options.crb_samples = 0;
  const research::ExperimentResult r = research::RunStability(options);
  ASSERT_TRUE(r.error.empty()) << r.error;
  const research::ErrorStats& lls = Row(r, "lls", 1.0).errors;
  const research::ErrorStats& nl = Row(r, "nl", 1.0).errors;
  EXPECT_LE(nl.dir_mean_deg, lls.dir_mean_deg);
  EXPECT_LE(nl.dir_median_deg, lls.dir_median_deg);
  EXPECT_LE(nl.dist_mean_pct, lls.dist_mean_pct);
  EXPECT_LE(nl.dist_median_pct, lls.dist_median_pct);
  EXPECT_TRUE(std::isnan(Row(r, "nl", 1.0).crb.rot_deg));  // no bound requested
}

// Thesis 5.1.3: errors fall with the number of poses.
TEST(ExperimentsTest, MorePosesGiveSmallerErrors) {
  research::ExperimentOptions options = Small(150);
  const research::ExperimentResult r = research::RunPoses(options);
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_EQ(r.rows.size(), 2u * 21u);
  for (const char* series : {"lls", "nl"}) {
    const research::ExperimentRow& k4 = Row(r, series, 1.0, 4);
    const research::ExperimentRow& k24 = Row(r, series, 1.0, 24);
    EXPECT_LT(k24.errors.rot_mean_deg, k4.errors.rot_mean_deg) << series;
    EXPECT_LT(k24.errors.rot_median_deg, k4.errors.rot_median_deg) << series;
    EXPECT_LT(k24.errors.dir_mean_deg, k4.errors.dir_mean_deg) << series;
    EXPECT_LT(k24.errors.dir_median_deg, k4.errors.dir_median_deg) << series;
    EXPECT_LT(k24.crb.rot_deg, k4.crb.rot_deg) << series;
    EXPECT_LT(k24.crb.dir_deg, k4.crb.dir_deg) << series;
  }
}

// Thesis 5.2 on a coarse grid: without noise the translational model is exact for pure
// translation and the general model for any rotation; with noise the general model wins only
// for large rotations, so the boundary moves up with eps.
TEST(ExperimentsTest, MotionModelComparisonAndBoundary) {
  research::ExperimentOptions options = Small(100);
  options.model_eps_deg = {0.0, 1.0};
  options.alpha_max_deg = {0.0, 2.0, 25.0};
  const research::ExperimentResult r = research::RunMotionModel(options);
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_EQ(r.rows.size(), 2u * 2u * 3u);
  EXPECT_LT(Row(r, "translational", 0.0, 0, 0.0).errors.rot_mean_deg, 1e-6);
  EXPECT_LT(Row(r, "general", 0.0, 0, 2.0).errors.rot_mean_deg, 1e-6);
  EXPECT_GT(Row(r, "translational", 0.0, 0, 2.0).errors.rot_mean_deg, 1e-3);
  EXPECT_TRUE(std::isnan(Row(r, "translational", 1.0, 0, 2.0).errors.dir_mean_deg));
  EXPECT_LT(Row(r, "general", 1.0, 0, 25.0).errors.rot_mean_deg,
            Row(r, "translational", 1.0, 0, 25.0).errors.rot_mean_deg);
  EXPECT_GT(Row(r, "general", 1.0, 0, 2.0).errors.rot_mean_deg,
            Row(r, "translational", 1.0, 0, 2.0).errors.rot_mean_deg);
  ASSERT_EQ(r.boundary.size(), 2u);
  EXPECT_EQ(r.boundary[0].eps_deg, 0.0);
  EXPECT_EQ(r.boundary[0].value, 2.0);
  EXPECT_EQ(r.boundary[1].value, 25.0);
}

// Thesis 5.3 on a coarse grid: without noise the time-dependent model is exact for any scale
// drift and the time-fixed one only without drift.
TEST(ExperimentsTest, ScaleModelComparisonAndBoundary) {
  research::ExperimentOptions options = Small(100);
  options.model_eps_deg = {0.0, 1.0};
  options.max_scale_error_pct = {0.0, 20.0, 100.0};
  const research::ExperimentResult r = research::RunScaleModel(options);
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_EQ(r.rows.size(), 2u * 2u * 3u);
  for (double pct : {0.0, 20.0, 100.0}) {
    EXPECT_LT(Row(r, "time-dependent", 0.0, 0, pct).errors.dir_mean_deg, 1e-6) << pct;
  }
  EXPECT_LT(Row(r, "fixed", 0.0, 0, 0.0).errors.dir_mean_deg, 1e-6);
  EXPECT_GT(Row(r, "fixed", 0.0, 0, 20.0).errors.dir_mean_deg, 0.1);
  EXPECT_TRUE(std::isnan(Row(r, "time-dependent", 1.0, 0, 20.0).errors.scale_mean_pct));
  ASSERT_EQ(r.boundary.size(), 2u);
  EXPECT_EQ(r.boundary[0].value, 20.0);
  EXPECT_GE(r.boundary[1].value, 20.0);
}

TEST(ExperimentsTest, ResultsDependOnSeedNotOnThreads) {
  research::ExperimentOptions options = Small(60);
  options.stability_eps_deg = {0.5, 1.5};
  options.threads = 1;
  const std::string one = research::ExperimentCsv(research::RunStability(options));
  options.threads = 2;
  const std::string two = research::ExperimentCsv(research::RunStability(options));
  options.threads = 3;
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, research::ExperimentCsv(research::RunStability(options)));
  options.seed = 8;
  EXPECT_NE(one, research::ExperimentCsv(research::RunStability(options)));
}

TEST(ExperimentsTest, ProgressReachesTotalInOrder) {
  research::ExperimentOptions options = Small(50);
  options.stability_eps_deg = {0.0, 1.0, 2.0, 3.0};
  std::mutex mutex;
  std::vector<std::pair<int64_t, int64_t>> calls;
  options.progress = [&](int64_t done, int64_t total) {
    std::lock_guard<std::mutex> lock(mutex);
    calls.push_back({done, total});
  };
  research::RunStability(options);
  ASSERT_FALSE(calls.empty());
  EXPECT_LE(calls.size(), 10u);
  for (size_t i = 1; i < calls.size(); ++i) EXPECT_GT(calls[i].first, calls[i - 1].first);
  EXPECT_EQ(calls.back().first, 200);
  EXPECT_EQ(calls.back().second, 200);
}

TEST(ExperimentsTest, CsvHasExpectedColumnsAndRows) {
  research::ExperimentOptions options = Small(20);
  options.model_eps_deg = {0.0, 2.0};
  options.alpha_max_deg = {0.0, 10.0, 20.0};
  const research::ExperimentResult r = research::RunMotionModel(options);
  const std::vector<std::string> lines = Lines(research::ExperimentCsv(r));
  const std::string header =
      "experiment,series,eps_deg,num_poses,alpha_max_deg,max_scale_error_pct,usable,failed,"
      "rot_mean_deg,rot_rms_deg,rot_median_deg,dir_mean_deg,dir_rms_deg,dir_median_deg,"
      "dist_mean_pct,dist_rms_pct,dist_median_pct,scale_mean_pct,scale_rms_pct,"
      "scale_median_pct,crb_rot_deg,crb_dir_deg,crb_dist_pct,crb_scale_pct";
  ASSERT_EQ(lines.size(), 1u + 12u + 2u);  // header, 2 models x 2 eps x 3 alpha, 2 boundaries
  EXPECT_EQ(lines[0], header);
  for (const std::string& line : lines) EXPECT_EQ(Fields(line), 24) << line;
  EXPECT_EQ(lines[1].rfind("motion-model,translational,0,4,0,,20,0,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[13].rfind("motion-model,equal_error_boundary,0,4,", 0), 0u) << lines[13];
  EXPECT_EQ(Count(research::ExperimentCsv(r), "equal_error_boundary"), 2);
}

TEST(ExperimentsTest, WritesCsvSummaryAndWellFormedFigures) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("experiments_test_" + std::to_string(::getpid())) / "out";
  research::ExperimentOptions options = Small(20);
  options.stability_eps_deg = {0.0, 1.0, 2.0};
  options.model_eps_deg = {0.0, 1.0, 3.0};
  options.max_scale_error_pct = {0.0, 50.0};

  struct Expectation {
    research::ExperimentResult result;
    std::vector<std::string> figures;
    int series_per_figure;
  };
  const std::vector<Expectation> expectations = {
      // 4 panels x (mean, median, RMS, bound)
      {research::RunStability(options), {"fig5_1_lls.svg", "fig5_2_nl.svg"}, 16},
      // 2 models x 3 eps, plus the boundary
      {research::RunScaleModel(options), {"fig5_6.svg"}, 7},
  };
  for (const Expectation& e : expectations) {
    const auto written = research::WriteExperimentOutputs(e.result, dir.string());
    ASSERT_TRUE(written.ok()) << written.error();
    const std::string name = ToString(e.result.kind);
    EXPECT_EQ(written->size(), 2 + e.figures.size());
    EXPECT_EQ(ReadFile((dir / (name + ".csv")).string()), research::ExperimentCsv(e.result));
    const std::string summary = ReadFile((dir / (name + "_summary.txt")).string());
    EXPECT_EQ(summary, research::FormatSummary(e.result));
    EXPECT_NE(summary.find("notes:"), std::string::npos);
    for (const std::string& figure : e.figures) {
      const std::string svg = ReadFile((dir / figure).string());
      ASSERT_FALSE(svg.empty()) << figure;
      EXPECT_NE(svg.find("<svg "), std::string::npos);
      EXPECT_LT(svg.find("<svg "), 100u);
      EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n") << figure;
      EXPECT_EQ(Count(svg, "<g class=\"series\""), e.series_per_figure) << figure;
      EXPECT_EQ(Count(svg, "<g "), Count(svg, "</g>")) << figure;
    }
  }
  // The stability summary shows the bound next to the errors and says what it bounds.
  const std::string summary = research::FormatSummary(expectations[0].result);
  EXPECT_NE(summary.find("CRB (RMS)"), std::string::npos);
  EXPECT_NE(summary.find("RMS"), std::string::npos);
  EXPECT_NE(summary.find("linear in eps"), std::string::npos);
  const std::string scale_summary = research::FormatSummary(expectations[1].result);
  EXPECT_NE(scale_summary.find("equal-error boundary"), std::string::npos);

  // An unwritable directory is reported, not thrown.
  const std::filesystem::path file = dir / "not_a_dir";
  std::ofstream(file.string()) << "x";
  const auto failed = research::WriteExperimentOutputs(expectations[0].result, (file / "sub").string());
  EXPECT_FALSE(failed.ok());
  std::filesystem::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace rigcal
