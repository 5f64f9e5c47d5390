// Evaluation report (text and JSON) and plot files: content, alignment, well-formed data and
// script, and (when gnuplot is on PATH) the SVGs it draws. No assertion on pixels.
#include "rowloc/sim/evaluation_report.hpp"
#include "rowloc/sim/report_plots.hpp"

#include "test_support.hpp"

#include <Eigen/LU>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace rowloc::sim {
namespace {

using ::testing::HasSubstr;

std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Fixture {
  formats::TruthStream truth;
  formats::EstimateStream estimates;
  EvaluationResult result;
  ReportInputs inputs;
};

Fixture EvaluateShippedFixture() {
  const auto dir = test::SourceDir() / "tests/data/evaluate";
  Fixture f;
  f.truth = formats::ReadTruthStream(dir / "truth.ndjson");
  f.estimates = formats::ReadEstimateStream(dir / "estimates.ndjson");
  f.result = Evaluate(f.truth, f.estimates, {});
  f.inputs = {"truth.ndjson", "estimates.ndjson", "", f.estimates.updates.size(), 0, 0};
  return f;
}

TEST(ReportText, HasEverySectionAndAlignedTables) {
  const Fixture f = EvaluateShippedFixture();
  const std::string text = FormatReportText(f.result, f.inputs);
  EXPECT_THAT(text, HasSubstr("along/across reference: true heading (no row map given)"));
  EXPECT_THAT(text, HasSubstr("position, total [m]"));
  EXPECT_THAT(text, HasSubstr("heading (signed) [deg]"));
  EXPECT_THAT(text, HasSubstr("Normalized estimation error squared"));
  EXPECT_THAT(text, HasSubstr("gnss"));
  EXPECT_THAT(text, HasSubstr("Drift after loss of absolute fixes"));
  EXPECT_THAT(text, HasSubstr("front_left"));
  // Within the pose table every full row has the same width (right-aligned columns).
  std::istringstream in(text);
  std::string line;
  std::set<std::size_t> widths;
  bool in_pose_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("  error ", 0) == 0) in_pose_table = true;
    if (in_pose_table && line.empty()) break;
    if (in_pose_table && line.find("signed mean") == std::string::npos) widths.insert(line.size());
  }
  EXPECT_EQ(widths.size(), 1u) << text;
}

TEST(ReportText, SaysWhatIsNotReported) {
  formats::TruthStream truth;
  truth.samples = {formats::TruthSample{0.0, {0.0, 0.0}, 0.0, true, {}, {}, 2},
                   formats::TruthSample{1.0, {1.0, 0.0}, 0.0, true, {}, {}, 3}};
  formats::EstimateStream est;
  est.estimates = {formats::EstimateSample{0.5, {0.5, 0.1}, std::nullopt, std::nullopt, {}, {}, 2}};
  const std::string text = FormatReportText(Evaluate(truth, est, {}), {});
  EXPECT_THAT(text, HasSubstr("heading: not reported"));
  EXPECT_THAT(text, HasSubstr("NEES: not reported"));
  EXPECT_THAT(text, HasSubstr("NIS: not reported"));
  EXPECT_THAT(text, HasSubstr("no GNSS outage"));
  EXPECT_THAT(text, HasSubstr("Slip error: not reported"));
  EXPECT_THAT(text, HasSubstr("Rolling radius: not reported"));
}

TEST(Report, RollingRadiusSectionInTextAndJson) {
  formats::TruthStream truth;
  truth.samples = {formats::TruthSample{0.0, {0.0, 0.0}, 0.0, true, {}, {{"left", 0.16}}, 2},
                   formats::TruthSample{1.0, {1.0, 0.0}, 0.0, true, {}, {{"left", 0.16}}, 3}};
  formats::EstimateStream est;
  for (int k = 0; k < 4; ++k) {
    formats::EstimateSample e{0.25 * k, {0.25 * k, 0.0}, std::nullopt, std::nullopt, {}, {},
                              static_cast<std::size_t>(k + 2)};
    e.wheel_calibration = {{"left", 0.162, k == 3 ? 0.0 : 0.001, 0.5, 0.1}};
    est.estimates.push_back(e);
  }
  const EvaluationResult r = Evaluate(truth, est, {});
  const std::string text = FormatReportText(r, {});
  EXPECT_THAT(text, HasSubstr("Rolling radius per wheel"));
  EXPECT_THAT(text, HasSubstr("0.16200 +- 0.00000"));  // the last estimate's R_w and sigma
  EXPECT_THAT(text, HasSubstr("left: 1 estimates with sigma 0: no NEES"));
  const auto j = nlohmann::json::parse(FormatReportJson(r, {}));
  const auto& left = j.at("rolling_radius").at(0);
  EXPECT_EQ(left.at("wheel"), "left");
  EXPECT_NEAR(left.at("error_m").at("mean").get<double>(), 0.002, 1e-12);
  EXPECT_NEAR(left.at("nees").at("mean").get<double>(), 4.0, 1e-9);  // (2 mm / 1 mm)^2
  EXPECT_EQ(left.at("nees").at("count").get<std::size_t>(), 3u);
  EXPECT_EQ(left.at("zero_sigma_count").get<std::size_t>(), 1u);
  EXPECT_DOUBLE_EQ(left.at("final_truth_m").get<double>(), 0.16);
}

TEST(ReportJson, CarriesTheNumbers) {
  const Fixture f = EvaluateShippedFixture();
  const auto j = nlohmann::json::parse(FormatReportJson(f.result, f.inputs));
  EXPECT_EQ(j.at("schema"), "rowloc-evaluation/1");
  EXPECT_EQ(j.at("reference"), "true_heading");
  EXPECT_DOUBLE_EQ(j.at("position").at("total_m").at("rms").get<double>(), f.result.position.total_m.rms);
  EXPECT_DOUBLE_EQ(j.at("position").at("across_signed_mean_m").get<double>(), f.result.position.across_signed_mean_m);
  EXPECT_DOUBLE_EQ(j.at("nees").at("mean").get<double>(), f.result.nees.mean);
  EXPECT_EQ(j.at("nees").at("count").get<std::size_t>(), 21u);
  const auto& gnss = j.at("innovations").at(0);
  EXPECT_EQ(gnss.at("sensor"), "gnss");
  EXPECT_EQ(gnss.at("gated_out_count").get<int>(), 1);
  EXPECT_EQ(gnss.at("whiteness").at("autocorrelation").size(), f.result.innovations[0].whiteness.autocorrelation.size());
  ASSERT_EQ(j.at("drift").size(), 1u);
  EXPECT_DOUBLE_EQ(j.at("drift").at(0).at("start_s").get<double>(), 8.0);
  EXPECT_DOUBLE_EQ(j.at("drift").at(0).at("end_s").get<double>(), 15.0);
  EXPECT_EQ(j.at("slip").size(), 2u);
  EXPECT_FALSE(j.at("nees").contains("batch_means"));  // 21 samples: fewer than 2 per batch
}

TEST(ReportJson, CarriesTheBatchMeansIntervalOfCorrelatedSamples) {
  EvaluationResult r;
  std::vector<double> nees;
  for (int k = 0; k < 400; ++k) nees.push_back(k % 2 == 0 ? 1.0 : 5.0);  // mean 3, tau 1
  r.nees = SummarizeConsistency(nees, std::vector<int>(nees.size(), 3));
  ASSERT_TRUE(r.nees.batch_means.has_value());
  auto j = nlohmann::json::parse(FormatReportJson(r, {}));
  const auto& b = j.at("nees").at("batch_means");
  EXPECT_EQ(b.at("batches").get<std::size_t>(), 20u);
  EXPECT_EQ(b.at("batch_length").get<std::size_t>(), 20u);
  EXPECT_DOUBLE_EQ(b.at("lower").get<double>(), r.nees.batch_means->lower);
  EXPECT_DOUBLE_EQ(b.at("upper").get<double>(), r.nees.batch_means->upper);
  EXPECT_TRUE(b.at("expected_inside").get<bool>());
  EXPECT_DOUBLE_EQ(j.at("nees").at("correlation_time_samples").get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j.at("nees").at("effective_sample_count").get<double>(), 400.0);
  std::string text = FormatReportText(r, {});
  EXPECT_THAT(text, HasSubstr("batch-means 95 % interval"));
  EXPECT_THAT(text, HasSubstr("holds dof"));
  // Correlated over ~100 samples: 400 samples are too few batches of 4 tau: no interval, said so.
  nees.clear();
  for (int k = 0; k < 400; ++k) nees.push_back(k % 200 < 100 ? 1.0 : 5.0);
  r.nees = SummarizeConsistency(nees, std::vector<int>(nees.size(), 3));
  EXPECT_GT(r.nees.correlation_time_samples, 50.0);
  EXPECT_FALSE(r.nees.batch_means.has_value());
  j = nlohmann::json::parse(FormatReportJson(r, {}));
  EXPECT_FALSE(j.at("nees").contains("batch_means"));
  text = FormatReportText(r, {});
  EXPECT_THAT(text, HasSubstr("too short"));
}

TEST(ReportFiles, WritesTextAndJson) {
  const Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  WriteReport(f.result, f.inputs, dir / "nested/report");
  EXPECT_EQ(ReadAll(dir / "nested/report/report.txt"), FormatReportText(f.result, f.inputs));
  const auto j = nlohmann::json::parse(ReadAll(dir / "nested/report/report.json"));
  EXPECT_EQ(j.at("schema"), "rowloc-evaluation/1");
}

bool IsFiniteNumber(const std::string& token) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size() && std::isfinite(v);
}

/// The 'quoted' names ending in .dat or .svg in a gnuplot script.
std::vector<std::string> QuotedFileNames(const std::string& script) {
  std::vector<std::string> names;
  std::size_t open = script.find('\'');
  while (open != std::string::npos) {
    const std::size_t close = script.find('\'', open + 1);
    if (close == std::string::npos) break;
    const std::string name = script.substr(open + 1, close - open - 1);
    if (name.ends_with(".dat") || name.ends_with(".svg")) names.push_back(name);
    open = script.find('\'', close + 1);
  }
  return names;
}

/// Every data line: `columns` fields, each a number or '?'.
void ExpectWellFormedData(const std::filesystem::path& path, std::size_t columns) {
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::string line;
  std::size_t data_lines = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string token;
    std::size_t n = 0;
    while (fields >> token) {
      EXPECT_TRUE(token == "?" || IsFiniteNumber(token)) << path << ": " << token;
      ++n;
    }
    EXPECT_EQ(n, columns) << path << ": " << line;
    ++data_lines;
  }
  EXPECT_GT(data_lines, 0u) << path;
}

PlotFiles WriteFixturePlots(const Fixture& f, const std::filesystem::path& dir) {
  geometry::RowMap map;
  map.rows = {{"r1", {{-1.0, 1.25}, {21.0, 1.25}}, false}, {"r2", {{-1.0, 3.75}, {21.0, 3.75}, {21.0, 4.0}}, true}};
  return WritePlotFiles(f.result, f.truth, f.estimates, map, dir);
}

TEST(Plots, DataFilesAndScriptAreWellFormed) {
  const Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  const PlotFiles files = WriteFixturePlots(f, dir.path());
  ExpectWellFormedData(dir / "truth.dat", 4);
  ExpectWellFormedData(dir / "estimate.dat", 4);
  ExpectWellFormedData(dir / "errors.dat", 9);
  ExpectWellFormedData(dir / "ellipses.dat", 2);
  ExpectWellFormedData(dir / "rows.dat", 2);
  ExpectWellFormedData(dir / "hist_across.dat", 2);
  ExpectWellFormedData(dir / "nees.dat", 4);
  ExpectWellFormedData(dir / "nis_0_gnss.dat", 4);
  const std::string script = ReadAll(dir / files.script);
  // Every file the script reads exists; every SVG it writes is listed.
  std::set<std::string> svgs;
  std::size_t data_references = 0;
  for (const std::string& name : QuotedFileNames(script)) {
    if (name.ends_with(".dat")) {
      ++data_references;
      EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
    } else {
      svgs.insert(name);
    }
  }
  EXPECT_GE(data_references, 8u);
  EXPECT_EQ(svgs, std::set<std::string>(files.svg_files.begin(), files.svg_files.end()));
  EXPECT_EQ(files.svg_files.size(), 4u);
  // 2-sigma ellipses every second: 21 estimates with covariance, 49 points each.
  std::ifstream ellipses(dir / "ellipses.dat");
  std::size_t blocks = 0;
  std::string line, previous = "x";
  while (std::getline(ellipses, line)) {
    if (line.empty() && !previous.empty()) ++blocks;
    previous = line;
  }
  EXPECT_EQ(blocks, 21u);
}

TEST(Plots, EllipseIsTheKSigmaContour) {
  Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  PlotOptions options;
  options.k_sigma = 3.0;
  options.ellipse_interval_s = 100.0;  // only the first estimate
  WritePlotFiles(f.result, f.truth, f.estimates, std::nullopt, dir.path(), options);
  std::ifstream in(dir / "ellipses.dat");
  std::string line;
  const formats::EstimateSample& e = f.estimates.estimates.front();
  const Eigen::Matrix2d inv = e.covariance->topLeftCorner<2, 2>().inverse();
  std::size_t points = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream xy(line);
    Eigen::Vector2d p;
    xy >> p.x() >> p.y();
    const Eigen::Vector2d d = p - e.position_m;
    EXPECT_NEAR(d.dot(inv * d), 9.0, 1e-9);  // Mahalanobis distance k = 3
    ++points;
  }
  EXPECT_EQ(points, 49u);
}

TEST(Plots, RejectBadOptions) {
  const Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  PlotOptions bad;
  bad.k_sigma = 0.0;
  EXPECT_THROW(WritePlotFiles(f.result, f.truth, f.estimates, std::nullopt, dir.path(), bad), std::invalid_argument);
  bad = {};
  bad.histogram_bins = 0;
  EXPECT_THROW(WritePlotFiles(f.result, f.truth, f.estimates, std::nullopt, dir.path(), bad), std::invalid_argument);
}

TEST(Plots, GnuplotDrawsNonEmptySvgsEvenInADirectoryWithAQuote) {
  if (!FindExecutableOnPath("gnuplot")) GTEST_SKIP() << "gnuplot is not on PATH";
  const Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  const PlotFiles files = WriteFixturePlots(f, dir / "it's a dir; echo x");
  const GnuplotRun run = RunGnuplot(files);
  ASSERT_TRUE(run.ran) << run.message;
  EXPECT_EQ(run.exit_code, 0) << run.message;
  for (const std::string& svg : files.svg_files) {
    const std::string content = ReadAll(files.directory / svg);
    EXPECT_THAT(content, HasSubstr("<svg")) << svg;
    EXPECT_THAT(content, HasSubstr("</svg>")) << svg;
  }
}

TEST(Plots, SensorNamesCannotInjectGnuplotCommands) {
  Fixture f = EvaluateShippedFixture();
  for (formats::UpdateRecord& u : f.estimates.updates) u.sensor = "g'ps\nsystem 'touch injected'";
  f.result = Evaluate(f.truth, f.estimates, {});
  test::ScratchDir dir;
  const PlotFiles files = WritePlotFiles(f.result, f.truth, f.estimates, std::nullopt, dir.path());
  const std::string script = ReadAll(dir / files.script);
  EXPECT_THAT(script, ::testing::Not(HasSubstr("\nsystem")));
  EXPECT_THAT(script, HasSubstr("'NIS g''ps system ''touch injected'' (band: accepted updates)'"));
  if (!FindExecutableOnPath("gnuplot")) return;
  const GnuplotRun run = RunGnuplot(files);
  EXPECT_EQ(run.exit_code, 0) << run.message;
  EXPECT_FALSE(std::filesystem::exists(dir / "injected"));
}

TEST(Plots, GnuplotCopesWithoutCovarianceHeadingOrUpdates) {
  if (!FindExecutableOnPath("gnuplot")) GTEST_SKIP() << "gnuplot is not on PATH";
  Fixture f = EvaluateShippedFixture();
  for (formats::EstimateSample& e : f.estimates.estimates) {
    e.covariance.reset();
    e.phi_rad.reset();
  }
  f.estimates.updates.clear();
  f.result = Evaluate(f.truth, f.estimates, {});
  test::ScratchDir dir;
  const PlotFiles files = WritePlotFiles(f.result, f.truth, f.estimates, std::nullopt, dir.path());
  EXPECT_EQ(files.svg_files.size(), 3u);  // no consistency plot
  const GnuplotRun run = RunGnuplot(files);
  EXPECT_EQ(run.exit_code, 0) << run.message;
  for (const std::string& svg : files.svg_files) EXPECT_THAT(ReadAll(dir / svg), HasSubstr("</svg>")) << svg;
}

TEST(Plots, MissingGnuplotIsReportedNotFatal) {
  const Fixture f = EvaluateShippedFixture();
  test::ScratchDir dir;
  const PlotFiles files = WriteFixturePlots(f, dir.path());
  const char* old_path = std::getenv("PATH");
  const std::string saved = old_path ? old_path : "";
  ::setenv("PATH", (dir / "no-such-bin").c_str(), 1);
  const GnuplotRun run = RunGnuplot(files);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_FALSE(run.ran);
  EXPECT_THAT(run.message, HasSubstr("gnuplot not found on PATH"));
  EXPECT_TRUE(std::filesystem::exists(dir / "plots.gp"));
}

}  // namespace
}  // namespace rowloc::sim
