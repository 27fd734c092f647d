// SPDX-License-Identifier: Apache-2.0
// `rigcal report`'s data and page: a history log made by the online estimator, a pose log, a
// result file, a truth, damaged and foreign inputs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>

#include "report/history_fixture.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/report/report_html.h"
#include "rigcal/report/report_input.h"

namespace rigcal::report::report_test {
namespace {

using ::testing::HasSubstr;

class ReportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { files_ = new HistoryFiles(MakeHistory("data")); }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(files_->dir);
    delete files_;
  }
  static HistoryFiles* files_;
};
HistoryFiles* ReportTest::files_ = nullptr;

TEST_F(ReportTest, HistoryLogGivesEveryMessageAsHistory) {
  ASSERT_GT(files_->extrinsics, 50);
  auto data = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  EXPECT_TRUE(data->from_log);
  EXPECT_EQ(data->master, "cam0");
  EXPECT_THAT(data->slaves, ::testing::ElementsAre("cam1", "cam2"));
  EXPECT_EQ(data->extrinsics_messages, files_->extrinsics);
  EXPECT_EQ(data->status_messages, files_->status);
  for (const std::string& slave : data->slaves) {
    const auto& samples = data->estimates.at(slave);
    ASSERT_EQ(static_cast<int>(samples.size()), files_->extrinsics);
    for (size_t k = 1; k < samples.size(); ++k) EXPECT_GT(samples[k].t_s, samples[k - 1].t_s);
    // 600 frames at 20 Hz, one message every 10 frames from frame 9: 0 .. 29.5 s.
    EXPECT_NEAR(samples.back().t_s - samples.front().t_s, 29.5, 0.1);
  }
  EXPECT_THAT(data->cameras, ::testing::ElementsAre("cam0", "cam1", "cam2"));
  // The fixture's cam1 is lost between frames 300 and 340; cam2 counts a drop every 100.
  int lost = 0;
  for (const CameraHealthSample& h : data->health.at("cam1")) lost += h.vo_state == 2;
  EXPECT_EQ(lost, 4);
  EXPECT_EQ(data->health.at("cam2").back().dropped, 5);
  // cam1 runs free (RIGCAL_STATUS version 4): its clock offset, unknown while re-estimated
  // after the restart at frame 400, and the jump.
  EXPECT_TRUE(data->free_running);
  const auto& cam1 = data->health.at("cam1");
  EXPECT_DOUBLE_EQ(cam1.front().time_offset_ms, 40.0);
  EXPECT_EQ(cam1.front().clock_jumps, 0);
  EXPECT_DOUBLE_EQ(cam1.back().time_offset_ms, -2500.0);
  EXPECT_EQ(cam1.back().clock_jumps, 1);
  int unknown = 0;
  for (const CameraHealthSample& h : cam1) unknown += std::isnan(h.time_offset_ms);
  EXPECT_EQ(unknown, 10);
  EXPECT_TRUE(std::isnan(data->health.at("cam0").front().time_offset_ms)) << "the reference";
  // The last message is the final table; without poses no per-motion analysis, and a note
  // says why.
  ASSERT_EQ(data->final_result.slaves.size(), 2u);
  EXPECT_FALSE(data->motions.has_value());
  EXPECT_THAT(data->notes, ::testing::Contains(HasSubstr("no per-motion residua")));
}

TEST_F(ReportTest, PosesGiveResiduaAgainstTheFinalEstimate) {
  auto data = LoadReport({files_->history_log, files_->pose_log, files_->truth});
  ASSERT_TRUE(data.ok()) << data.error();
  ASSERT_TRUE(data->motions.has_value());
  EXPECT_EQ(data->motions->pairs, "walk");
  for (const std::string& slave : data->slaves) {
    const SlaveMotions& m = data->motions->slaves.at(slave);
    ASSERT_GT(m.samples.size(), 50u) << slave;
    EXPECT_GT(m.scale_threshold, 0.0);
    // Poses with 0.02 deg noise against a converged estimate: the rotation residua are of the
    // noise's size, and the measured scales that pass the threshold centre on the truth.
    std::vector<double> rotation, scales;
    for (const MotionSample& s : m.samples) {
      rotation.push_back(s.rotation_deg);
      if (s.scale_used) scales.push_back(s.measured_scale);
      EXPECT_EQ(s.scale_used, std::abs(s.slave_axis_dot) > m.scale_threshold);
    }
    std::sort(rotation.begin(), rotation.end());
    EXPECT_LT(rotation[rotation.size() / 2], 0.2) << slave;
    ASSERT_GT(scales.size(), 10u);
    std::sort(scales.begin(), scales.end());
    const double truth_scale = files_->truth_rig.at(slave).scale;
    EXPECT_NEAR(scales[scales.size() / 2], truth_scale, 0.02 * truth_scale) << slave;
  }
  // The truth is in the estimate's unit (the drive's master unit: no alignment needed).
  ASSERT_EQ(data->truth.size(), 2u);
  EXPECT_NEAR((data->truth.at("cam1").C - files_->truth_rig.at("cam1").C).norm(), 0.0, 1e-9);
}

TEST_F(ReportTest, PageHasEveryPlotWithData) {
  auto data = LoadReport({files_->history_log, files_->pose_log, files_->truth});
  ASSERT_TRUE(data.ok()) << data.error();
  const std::string html = RenderReportHtml(*data);
  // rig view, 2 histories, 2 x (scales, residua, histograms), health: 10 plots, none missing.
  EXPECT_EQ(CountOf(html, "<figure class=\"plot\""), 10);
  EXPECT_EQ(CountOf(html, "<figure class=\"plot missing\""), 0);
  // The health figure shows the clock of the free-running cam1.
  EXPECT_GE(CountOf(html, "clock offset to the master"), 1);
  EXPECT_GE(CountOf(html, "clock jumps (cumulative)"), 1);
  // Self-contained: no external references.
  EXPECT_EQ(CountOf(html, "src="), 0);
  EXPECT_EQ(CountOf(html, "href="), 0);
  EXPECT_EQ(CountOf(html, "@import"), 0);
  // Every series of the history has points; bands for the σ; truth lines; frusta of 3 cameras
  // and 2 truths in two views.
  EXPECT_EQ(CountOf(html, "data-points=\"0\""), 0);
  EXPECT_GT(CountOf(html, "class=\"band\""), 10);
  EXPECT_GT(CountOf(html, "class=\"reference\""), 10);
  EXPECT_EQ(CountOf(html, "class=\"frustum\""), 10);
  // Clip-path ids are unique in the page.
  std::set<std::string> ids;
  const std::regex id_re("<clipPath id=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), id_re);
       it != std::sregex_iterator(); ++it) {
    EXPECT_TRUE(ids.insert((*it)[1]).second) << "duplicate id " << (*it)[1];
  }
  EXPECT_GT(ids.size(), 10u);
  // The table carries the thesis's error-model columns and the truth rows.
  EXPECT_EQ(CountOf(html, "position direction error [°]"), 1);
  EXPECT_EQ(CountOf(html, "<table class=\"final errors\">"), 1);
  EXPECT_EQ(CountOf(html, "<tr class=\"truth\">"), 2);
}

TEST_F(ReportTest, ResultFileGivesTableAndRigButNoHistory) {
  auto history = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(history.ok()) << history.error();
  const std::string result = (files_->dir / "result.yaml").string();
  ASSERT_TRUE(io::WriteResultYaml(result, history->final_result).ok());
  auto data = LoadReport({result, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  EXPECT_FALSE(data->from_log);
  EXPECT_THAT(data->slaves, ::testing::ElementsAre("cam1", "cam2"));
  const std::string html = RenderReportHtml(*data);
  EXPECT_EQ(CountOf(html, "no history in a result file"), 4);  // note, 2 histories, health
  EXPECT_EQ(CountOf(html, "<figure class=\"plot\""), 1);       // the rig
  EXPECT_EQ(CountOf(html, "class=\"frustum\""), 6);
  // With the poses the per-motion plots come back.
  auto with_poses = LoadReport({result, files_->pose_log, ""});
  ASSERT_TRUE(with_poses.ok()) << with_poses.error();
  EXPECT_EQ(CountOf(RenderReportHtml(*with_poses), "<figure class=\"plot\""), 7);
}

TEST_F(ReportTest, DamagedLogIsUsedUpToTheDamage) {
  const std::string damaged = (files_->dir / "damaged.lcmlog").string();
  std::filesystem::copy_file(files_->history_log, damaged,
                             std::filesystem::copy_options::overwrite_existing);
  const auto size = std::filesystem::file_size(damaged);
  std::filesystem::resize_file(damaged, size - 100);
  auto data = LoadReport({damaged, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  EXPECT_LT(data->extrinsics_messages, files_->extrinsics + 1);
  EXPECT_THAT(data->notes, ::testing::Contains(HasSubstr("truncated or corrupt event after byte")));
}

TEST_F(ReportTest, BadInputsAreNamed) {
  const std::string junk = (files_->dir / "junk.bin").string();
  std::ofstream(junk) << "\x01\x02 this is neither";
  auto data = LoadReport({junk, "", ""});
  ASSERT_FALSE(data.ok());
  EXPECT_THAT(data.error(), HasSubstr(junk));
  EXPECT_THAT(data.error(), HasSubstr("nor an LCM log"));

  // A pose log has no history.
  auto poses_only = LoadReport({files_->pose_log, "", ""});
  ASSERT_FALSE(poses_only.ok());
  EXPECT_THAT(poses_only.error(), HasSubstr("no valid RIGCAL_EXTRINSICS"));

  // A truth that lacks a slave.
  const std::string partial = (files_->dir / "partial_truth.yaml").string();
  ASSERT_TRUE(io::WriteRigYaml(partial, {{"cam1", files_->truth_rig.at("cam1")}}).ok());
  auto no_truth = LoadReport({files_->history_log, "", partial});
  ASSERT_FALSE(no_truth.ok());
  EXPECT_THAT(no_truth.error(), HasSubstr("no truth for slave 'cam2'"));
}

TEST_F(ReportTest, WritesAtomicallyAndNamesAnUnwritablePath) {
  auto data = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  const std::string path = (files_->dir / "report.html").string();
  ASSERT_TRUE(WriteReportHtml(path, *data).ok());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), RenderReportHtml(*data));
  const Status failed = WriteReportHtml((files_->dir / "missing" / "r.html").string(), *data);
  ASSERT_FALSE(failed.ok());
  EXPECT_THAT(failed.message(), HasSubstr("missing/r.html"));
}

}  // namespace
}  // namespace rigcal::report::report_test
