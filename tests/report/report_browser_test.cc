// SPDX-License-Identifier: Apache-2.0
// `rigcal report`'s page in a real browser: headless Chromium renders it, takes a screenshot,
// and dumps the DOM after the page's script ran; every plot must have rendered with data and
// the console must stay empty. A page with a broken plot and a script error proves the check
// fails. Skipped without chromium (failed under CI=true).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "report/history_fixture.h"
#include "rigcal/report/report_html.h"
#include "rigcal/report/report_input.h"
#include "support/skip.h"

namespace rigcal::report::report_test {
namespace {

std::string FindChromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const std::string probe = std::string("command -v ") + name + " >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return name;
  }
  return "";
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct BrowserRun {
  int exit_code = -1;
  std::string dom;
  std::string console;  // the console lines of Chromium's log
  std::string screenshot;
};

// Runs headless Chromium twice on `html_path`: a screenshot, and the DOM after the scripts ran
// (with the browser log on stderr, whose CONSOLE lines are the page's console).
BrowserRun RunBrowser(const std::string& chromium, const std::string& html_path,
                      const std::string& out_prefix) {
  BrowserRun run;
  run.screenshot = out_prefix + ".png";
  const std::string flags =
      " --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir=" + out_prefix +
      ".profile --window-size=1280,6000 ";
  const std::string shot = chromium + flags + "--screenshot=" + run.screenshot + " file://" +
                           html_path + " >" + out_prefix + ".shot.log 2>&1";
  run.exit_code = std::system(shot.c_str());
  const std::string dump = chromium + flags + "--enable-logging=stderr --v=0 --dump-dom file://" +
                           html_path + " >" + out_prefix + ".dom 2>" + out_prefix + ".stderr";
  const int dump_code = std::system(dump.c_str());
  if (run.exit_code == 0) run.exit_code = dump_code;
  run.dom = ReadText(out_prefix + ".dom");
  std::istringstream log(ReadText(out_prefix + ".stderr"));
  for (std::string line; std::getline(log, line);) {
    if (line.find(":CONSOLE(") != std::string::npos ||
        line.find(":CONSOLE:") != std::string::npos || line.find("Uncaught") != std::string::npos) {
      run.console += line + "\n";
    }
  }
  return run;
}

int Attribute(const std::string& dom, const std::string& name) {
  const std::regex re(name + "=\"([0-9]+)\"");
  std::smatch m;
  return std::regex_search(dom, m, re) ? std::stoi(m[1]) : -1;
}

class ReportBrowserTest : public ::testing::Test {
 protected:
  void SetUp() override {
    chromium_ = FindChromium();
    if (chromium_.empty()) {
      RIGCAL_SKIP_MISSING() << "chromium is not installed (scripts/install-deps.sh installs it)";
    }
  }
  std::string chromium_;
};

TEST_F(ReportBrowserTest, EveryPlotRendersAndTheConsoleIsEmpty) {
  // One directory for every run: the screenshot of the last run stays for a look.
  const HistoryFiles files = MakeHistory("browser", 600, false);
  auto data = LoadReport({files.history_log, files.pose_log, files.truth});
  ASSERT_TRUE(data.ok()) << data.error();
  const std::string html = (files.dir / "report.html").string();
  ASSERT_TRUE(WriteReportHtml(html, *data).ok());
  const int plots = CountOf(ReadText(html), "<figure class=\"plot\"");
  ASSERT_EQ(plots, 10);

  const BrowserRun run = RunBrowser(chromium_, html, (files.dir / "report").string());
  std::cout << "screenshot: " << run.screenshot << "\n";
  ASSERT_EQ(run.exit_code, 0);
  ASSERT_TRUE(std::filesystem::exists(run.screenshot));
  EXPECT_GT(std::filesystem::file_size(run.screenshot), 50'000u);
  EXPECT_EQ(Attribute(run.dom, "data-plots-expected"), plots) << run.dom.substr(0, 400);
  EXPECT_EQ(Attribute(run.dom, "data-plots-rendered"), plots);
  EXPECT_EQ(CountOf(run.dom, "data-rendered=\"true\""), plots);
  EXPECT_THAT(run.dom, ::testing::HasSubstr("(10/10 plots rendered)</title>"));
  EXPECT_EQ(run.console, "");
  std::filesystem::remove_all(files.dir / "report.profile");
}

// The check can fail: a plot whose series has no points and a script error are seen.
TEST_F(ReportBrowserTest, BrokenPageIsDetected) {
  const HistoryFiles files = MakeHistory("browser_broken");
  auto data = LoadReport({files.history_log, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  std::string page = RenderReportHtml(*data);
  // Empty the first history plot's series and add a failing script.
  const size_t history = page.find("data-plot=\"history-cam1\"");
  ASSERT_NE(history, std::string::npos);
  const std::regex points("data-points=\"[0-9]+\"");
  const size_t end = page.find("</figure>", history);
  std::string figure = page.substr(history, end - history);
  figure = std::regex_replace(figure, points, "data-points=\"0\"");
  page.replace(history, end - history, figure);
  page.replace(page.find("</body>"), 7, "<script>undefinedFunction();</script></body>");
  const std::string html = (files.dir / "broken.html").string();
  std::ofstream(html) << page;

  const BrowserRun run = RunBrowser(chromium_, html, (files.dir / "broken").string());
  ASSERT_EQ(run.exit_code, 0);
  const int expected = Attribute(run.dom, "data-plots-expected");
  EXPECT_GT(expected, 0);
  EXPECT_EQ(Attribute(run.dom, "data-plots-rendered"), expected - 1);
  EXPECT_THAT(run.console, ::testing::HasSubstr("undefinedFunction"));
  if (!HasFailure()) std::filesystem::remove_all(files.dir);
}

}  // namespace
}  // namespace rigcal::report::report_test
