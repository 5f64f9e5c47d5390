// Readers of the truth and estimate streams (docs/protocol.md §2-3): what they accept, and a
// clear error naming file, line and key for everything they reject.
#include "rowloc/formats/trajectory_streams.hpp"

#include "rowloc/formats/bounded_line_reader.hpp"

#include "counting_fill_buffer.hpp"
#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>
#include <string>

namespace rowloc::formats {
namespace {

using ::testing::HasSubstr;

const std::string kTruthHeader = R"({"type":"truth_header","protocol":"rowloc-truth/1","source":"test"})";
const std::string kEstimateHeader = R"({"type":"estimate_header","protocol":"rowloc-estimate/1"})";

TruthStream ParseTruth(const std::string& text) {
  std::istringstream in(text);
  return ParseTruthStream(in, "truth.ndjson");
}
EstimateStream ParseEstimates(const std::string& text) {
  std::istringstream in(text);
  return ParseEstimateStream(in, "est.ndjson");
}

TEST(TruthStream, ParsesSamplesIgnoringUnknownKeysAndSkippingUnknownTypes) {
  const TruthStream s = ParseTruth(
      kTruthHeader + "\n" +
      R"({"type":"truth","t":1.5,"x_m":10.2,"y_m":3.75,"phi_rad":0.25,"gnss_available":true,"future_key":[1,2],)"
      R"("wheels":{"front_left":{"slip":0.0125,"terrain":"grass"},"rear":{"speed_radps":3.0,"rolling_radius_m":0.16}}})" "\n\n"
      R"({"type":"annotation","text":"ignored"})" "\n"
      R"({"type":"truth","t":1.5,"x_m":10.3,"y_m":3.7,"phi_rad":-0.1,"gnss_available":false})" "\n");
  EXPECT_EQ(s.protocol, "rowloc-truth/1");
  ASSERT_EQ(s.samples.size(), 2u);
  EXPECT_EQ(s.skipped_lines, 1u);
  const TruthSample& a = s.samples[0];
  EXPECT_DOUBLE_EQ(a.t_s, 1.5);
  EXPECT_DOUBLE_EQ(a.position_m.x(), 10.2);
  EXPECT_DOUBLE_EQ(a.position_m.y(), 3.75);
  EXPECT_DOUBLE_EQ(a.phi_rad, 0.25);
  EXPECT_TRUE(a.gnss_available);
  ASSERT_EQ(a.wheel_slip.size(), 1u);  // "rear" has no slip
  EXPECT_DOUBLE_EQ(a.wheel_slip.at("front_left"), 0.0125);
  ASSERT_EQ(a.wheel_rolling_radius_m.size(), 1u);  // "front_left" has no radius
  EXPECT_DOUBLE_EQ(a.wheel_rolling_radius_m.at("rear"), 0.16);
  EXPECT_EQ(a.line, 2u);
  EXPECT_FALSE(s.samples[1].gnss_available);
  EXPECT_EQ(s.samples[1].line, 5u);  // blank line counted
}

TEST(TruthStream, AcceptsMinorVersions) {
  EXPECT_NO_THROW(ParseTruth(R"({"type":"truth_header","protocol":"rowloc-truth/1.4"})" "\n"));
}

TEST(EstimateStream, ParsesRequiredAndOptionalKeys) {
  const EstimateStream s = ParseEstimates(
      kEstimateHeader + "\n" +
      R"({"type":"estimate","t":0,"x_m":1,"y_m":2})" "\n"
      R"({"type":"estimate","t":1,"x_m":1,"y_m":2,"phi_rad":0.5,"covariance_xy_phi":[1e-4,0,0,0,2e-4,1e-6,0,1e-6,1e-5],)"
      R"("slip":{"front_left":0.013}})" "\n"
      R"({"type":"estimate","t":2,"x_m":1,"y_m":2,"covariance_xy_phi":[1,0.5,0.5,2],"wheel_calibration":)"
      R"({"right":{"rolling_radius_m":0.16,"rolling_radius_sigma_m":0.002,"slip_compliance":0.7,"slip_compliance_sigma":0.2},)"
      R"("left":{"rolling_radius_m":0.15,"rolling_radius_sigma_m":0,"slip_compliance":0,"slip_compliance_sigma":0.3}}})" "\n"
      R"({"type":"update","t":2,"sensor":"gnss","innovation":[0.01,-0.02],"innovation_covariance":[2e-4,0,0,2e-4],)"
      R"("nis":2.5,"accepted":false,"extra":null})" "\n");
  ASSERT_EQ(s.estimates.size(), 3u);
  EXPECT_FALSE(s.estimates[0].phi_rad);
  EXPECT_FALSE(s.estimates[0].covariance);
  EXPECT_TRUE(s.estimates[0].wheel_slip.empty());
  ASSERT_TRUE(s.estimates[1].covariance);
  EXPECT_EQ(s.estimates[1].covariance->rows(), 3);
  EXPECT_DOUBLE_EQ((*s.estimates[1].covariance)(1, 2), 1e-6);
  EXPECT_DOUBLE_EQ((*s.estimates[1].covariance)(1, 1), 2e-4);
  EXPECT_DOUBLE_EQ(*s.estimates[1].phi_rad, 0.5);
  EXPECT_DOUBLE_EQ(s.estimates[1].wheel_slip.at("front_left"), 0.013);
  EXPECT_EQ(s.estimates[2].covariance->rows(), 2);
  EXPECT_TRUE(s.estimates[1].wheel_calibration.empty());
  const auto& calibration = s.estimates[2].wheel_calibration;
  ASSERT_EQ(calibration.size(), 2u);
  EXPECT_EQ(calibration[0].wheel, "left");  // sorted by name
  EXPECT_DOUBLE_EQ(calibration[0].rolling_radius_m, 0.15);
  EXPECT_DOUBLE_EQ(calibration[0].slip_compliance_sigma, 0.3);
  EXPECT_EQ(calibration[1].wheel, "right");
  EXPECT_DOUBLE_EQ(calibration[1].rolling_radius_sigma_m, 0.002);
  EXPECT_DOUBLE_EQ(calibration[1].slip_compliance, 0.7);
  ASSERT_EQ(s.updates.size(), 1u);
  const UpdateRecord& u = s.updates[0];
  EXPECT_EQ(u.sensor, "gnss");
  EXPECT_EQ(u.innovation.size(), 2);
  EXPECT_DOUBLE_EQ(u.innovation(1), -0.02);
  EXPECT_DOUBLE_EQ(u.innovation_covariance(1, 1), 2e-4);
  EXPECT_DOUBLE_EQ(u.nis, 2.5);
  EXPECT_FALSE(u.accepted);
  EXPECT_EQ(u.line, 5u);
}

TEST(EstimateStream, AcceptsASingularCovariance) {
  // A known initial pose has a zero covariance; that is semi-definite, not an error.
  const EstimateStream s = ParseEstimates(kEstimateHeader + "\n" +
                                          R"({"type":"estimate","t":0,"x_m":1,"y_m":2,"covariance_xy_phi":[0,0,0,0]})" "\n");
  ASSERT_TRUE(s.estimates[0].covariance);
  EXPECT_EQ(s.estimates[0].covariance->norm(), 0.0);
}

TEST(EstimateStream, ReportsProgressByLineCount) {
  std::string text = kEstimateHeader + "\n" + std::string(2 * kProgressLines + 5, '\n');
  std::istringstream in(text);
  std::vector<std::size_t> calls;
  ParseEstimateStream(in, "est.ndjson", [&calls](std::size_t n) { calls.push_back(n); });
  EXPECT_THAT(calls, ::testing::ElementsAre(kProgressLines, 2 * kProgressLines));
}

TEST(StreamLines, ALineLongerThan1MiBIsRefusedAndOneAtTheLimitRead) {
  // Issue 26: these readers took a line whole (std::getline), however long: a 2 MiB line of valid
  // JSON was accepted, and /dev/zero as --calibration or as an evaluate input took GBs.
  const std::string line = R"({"type":"truth","t":1,"x_m":0,"y_m":0,"phi_rad":0,"gnss_available":true})";
  const std::string at_limit = line + std::string(kMaxProtocolLineBytes - line.size(), ' ');
  EXPECT_EQ(ParseTruth(kTruthHeader + "\n" + at_limit + "\r\n").samples.size(), 1u);
  const std::string over = line + std::string(2 * kMaxProtocolLineBytes, ' ');
  try {
    ParseTruth(kTruthHeader + "\n\n" + over + "\n");
    ADD_FAILURE() << "accepted a 2 MiB line";
  } catch (const StreamFormatError& e) {
    EXPECT_STREQ(e.what(), "truth.ndjson:3: line longer than 1 MiB (1048576 bytes, the protocol's limit)");
  }
  try {
    ParseEstimates(kEstimateHeader + "\n" + std::string(kMaxProtocolLineBytes + 1, ' '));  // unterminated too
    ADD_FAILURE() << "accepted a line of 1 MiB + 1 byte";
  } catch (const StreamFormatError& e) {
    EXPECT_STREQ(e.what(), "est.ndjson:2: line longer than 1 MiB (1048576 bytes, the protocol's limit)");
  }
}

TEST(StreamLines, AnEndlessLineIsRefusedAfter1MiB) {
  for (const bool truth : {true, false}) {
    rowloc::test::CountingFillBuffer zeros("", '\0', std::size_t{256} << 20);  // 256 MiB, no newline
    std::istream in(&zeros);
    try {
      if (truth) {
        ParseTruthStream(in, "zeros");
      } else {
        ParseEstimateStream(in, "zeros");
      }
      ADD_FAILURE() << "read a stream of zeros";
    } catch (const StreamFormatError& e) {
      EXPECT_STREQ(e.what(), "zeros:1: line longer than 1 MiB (1048576 bytes, the protocol's limit)");
    }
    EXPECT_LE(zeros.handed_out(), kMaxProtocolLineBytes + 2 + (std::size_t{1} << 16));
  }
}

TEST(StreamFiles, MissingFileIsAnErrorNamingIt) {
  try {
    ReadTruthStream("/nonexistent/truth.ndjson");
    FAIL() << "no error";
  } catch (const StreamFormatError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/truth.ndjson: cannot open file"));
  }
  EXPECT_THROW(ReadEstimateStream("/nonexistent/est.ndjson"), StreamFormatError);
}

TEST(StreamFiles, ReadsTheShippedFixtures) {
  const auto dir = test::SourceDir() / "tests/data/evaluate";
  EXPECT_EQ(ReadTruthStream(dir / "truth.ndjson").samples.size(), 41u);
  const EstimateStream e = ReadEstimateStream(dir / "estimates.ndjson");
  EXPECT_EQ(e.estimates.size(), 21u);
  EXPECT_EQ(e.updates.size(), 14u);
}

struct BadInput {
  const char* name;
  bool truth;               // which stream
  std::string body;         // lines after the header (or the whole text when header_included)
  std::string expected;     // substring of the message
  bool header_included = false;
};

class RejectsBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(RejectsBadInput, WithMessageNamingFileLineAndKey) {
  const BadInput& c = GetParam();
  const std::string text = c.header_included ? c.body : (c.truth ? kTruthHeader : kEstimateHeader) + "\n" + c.body;
  try {
    if (c.truth) {
      ParseTruth(text);
    } else {
      ParseEstimates(text);
    }
    FAIL() << "accepted: " << text;
  } catch (const StreamFormatError& e) {
    EXPECT_THAT(e.what(), HasSubstr(c.expected));
  }
}

const std::string kTruthLine = R"("type":"truth","t":1,"x_m":0,"y_m":0,"phi_rad":0,"gnss_available":true)";

/// An estimate line whose wheel_calibration holds wheel "l" with these fields.
std::string Calibration(const std::string& fields) {
  return R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"wheel_calibration":{"l":{)" + fields + "}}}\n";
}

INSTANTIATE_TEST_SUITE_P(
    TrajectoryStreams, RejectsBadInput,
    ::testing::Values(
        BadInput{"MalformedJson", true, "{" + kTruthLine + "\n", "truth.ndjson:2: malformed JSON"},
        BadInput{"NotAnObject", true, "[1,2]\n", "truth.ndjson:2: expected a JSON object"},
        BadInput{"MissingType", true, R"({"t":1})" "\n", "truth.ndjson:2: key 'type': missing required key"},
        BadInput{"MissingX", true, R"({"type":"truth","t":1,"y_m":0,"phi_rad":0,"gnss_available":true})" "\n",
                 "truth.ndjson:2: key 'x_m': missing required key"},
        BadInput{"MissingGnssFlag", true, R"({"type":"truth","t":1,"x_m":0,"y_m":0,"phi_rad":0})" "\n",
                 "key 'gnss_available': missing required key"},
        BadInput{"WrongType", true, R"({"type":"truth","t":"1","x_m":0,"y_m":0,"phi_rad":0,"gnss_available":true})" "\n",
                 "truth.ndjson:2: key 't': expected a number, got string"},
        BadInput{"BoolAsNumber", true, R"({"type":"truth","t":1,"x_m":0,"y_m":0,"phi_rad":0,"gnss_available":1})" "\n",
                 "key 'gnss_available': expected a boolean"},
        BadInput{"NonFinite", true, R"({"type":"truth","t":1,"x_m":1e999,"y_m":0,"phi_rad":0,"gnss_available":true})" "\n",
                 "truth.ndjson:2: malformed JSON: [json.exception.out_of_range.406] number overflow parsing '1e999'"},
        BadInput{"WheelSlipWrongType", true, "{" + kTruthLine + R"(,"wheels":{"fl":{"slip":"x"}}})" "\n",
                 "truth.ndjson:2: key 'wheels.fl.slip': expected a number"},
        BadInput{"TruthRadiusNotPositive", true, "{" + kTruthLine + R"(,"wheels":{"fl":{"rolling_radius_m":0}}})" "\n",
                 "truth.ndjson:2: key 'wheels.fl.rolling_radius_m': rolling radius must be > 0"},
        BadInput{"TruthRadiusWrongType", true, "{" + kTruthLine + R"(,"wheels":{"fl":{"rolling_radius_m":null}}})" "\n",
                 "truth.ndjson:2: key 'wheels.fl.rolling_radius_m': expected a number"},
        BadInput{"TimeBackwards", true, "{" + kTruthLine + "}\n" + R"({"type":"truth","t":0.5,"x_m":0,"y_m":0,"phi_rad":0,"gnss_available":true})" "\n",
                 "truth.ndjson:3: key 't': time goes backwards"},
        BadInput{"MajorVersion2", true, R"({"type":"truth_header","protocol":"rowloc-truth/2"})" "\n",
                 "truth.ndjson:1: key 'protocol': unsupported major version \"2\"", true},
        BadInput{"WrongFamily", true, R"({"type":"truth_header","protocol":"rowloc/1"})" "\n",
                 "key 'protocol': expected \"rowloc-truth/1\"", true},
        BadInput{"NoHeaderFirst", true, "{" + kTruthLine + "}\n", "truth.ndjson:1: key 'type': expected the \"truth_header\"",
                 true},
        BadInput{"EmptyStream", true, "\n\n", "truth.ndjson: empty stream", true},
        BadInput{"SecondHeader", true, kTruthHeader + "\n", "truth.ndjson:2: key 'type': second \"truth_header\""},
        BadInput{"EstimateMissingY", false, R"({"type":"estimate","t":0,"x_m":1})" "\n",
                 "est.ndjson:2: key 'y_m': missing required key"},
        BadInput{"EstimatePhiWrongType", false, R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"phi_rad":null})" "\n",
                 "key 'phi_rad': expected a number, got null"},
        BadInput{"CovarianceSize", false, R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"covariance_xy_phi":[1,0,0]})" "\n",
                 "key 'covariance_xy_phi': expected 9 (3x3) or 4 (2x2) numbers, got 3"},
        BadInput{"CovarianceElementType", false,
                 R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"covariance_xy_phi":[1,0,"0",1]})" "\n",
                 "key 'covariance_xy_phi[2]': expected a number"},
        BadInput{"CovarianceAsymmetric", false,
                 R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"covariance_xy_phi":[1,0.5,0,1]})" "\n",
                 "key 'covariance_xy_phi': matrix is not symmetric"},
        BadInput{"CovarianceIndefinite", false,
                 R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"covariance_xy_phi":[1,2,2,1]})" "\n",
                 "key 'covariance_xy_phi': matrix is not positive semi-definite"},
        BadInput{"InnovationCovarianceSingular", false,
                 R"({"type":"update","t":0,"sensor":"g","innovation":[1],"innovation_covariance":[0],"nis":1,"accepted":true})" "\n",
                 "key 'innovation_covariance': matrix is not positive definite"},
        BadInput{"SlipNotObject", false, R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"slip":[0.1]})" "\n",
                 "key 'slip': expected an object"},
        BadInput{"CalibrationNotObject", false, R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"wheel_calibration":[1]})" "\n",
                 "est.ndjson:2: key 'wheel_calibration': expected an object, got array"},
        BadInput{"CalibrationWheelNotObject", false,
                 R"({"type":"estimate","t":0,"x_m":1,"y_m":1,"wheel_calibration":{"l":0.16}})" "\n",
                 "key 'wheel_calibration.l': expected an object, got number"},
        BadInput{"CalibrationMissingSigma", false,
                 Calibration(R"("rolling_radius_m":0.16,"slip_compliance":0.7,"slip_compliance_sigma":0.2)"),
                 "key 'wheel_calibration.l.rolling_radius_sigma_m': missing required key"},
        BadInput{"CalibrationRadiusNotPositive", false,
                 Calibration(R"("rolling_radius_m":-0.16,"rolling_radius_sigma_m":0.002,"slip_compliance":0.7,"slip_compliance_sigma":0.2)"),
                 "key 'wheel_calibration.l.rolling_radius_m': must be > 0"},
        BadInput{"CalibrationNegativeCompliance", false,
                 Calibration(R"("rolling_radius_m":0.16,"rolling_radius_sigma_m":0.002,"slip_compliance":-0.1,"slip_compliance_sigma":0.2)"),
                 "key 'wheel_calibration.l.slip_compliance': must be >= 0"},
        BadInput{"CalibrationNegativeSigma", false,
                 Calibration(R"("rolling_radius_m":0.16,"rolling_radius_sigma_m":0.002,"slip_compliance":0.1,"slip_compliance_sigma":-0.2)"),
                 "key 'wheel_calibration.l.slip_compliance_sigma': must be >= 0"},
        BadInput{"CalibrationWrongType", false,
                 Calibration(R"("rolling_radius_m":"0.16","rolling_radius_sigma_m":0.002,"slip_compliance":0.1,"slip_compliance_sigma":0.2)"),
                 "key 'wheel_calibration.l.rolling_radius_m': expected a number, got string"},
        BadInput{"UpdateSizeMismatch", false,
                 R"({"type":"update","t":0,"sensor":"g","innovation":[1,2],"innovation_covariance":[1],"nis":1,"accepted":true})" "\n",
                 "est.ndjson:2: key 'innovation_covariance': expected 4 numbers"},
        BadInput{"UpdateEmptyInnovation", false,
                 R"({"type":"update","t":0,"sensor":"g","innovation":[],"innovation_covariance":[],"nis":1,"accepted":true})" "\n",
                 "key 'innovation': empty innovation"},
        BadInput{"UpdateMissingAccepted", false,
                 R"({"type":"update","t":0,"sensor":"g","innovation":[1],"innovation_covariance":[1],"nis":1})" "\n",
                 "key 'accepted': missing required key"},
        BadInput{"UpdateBeforeEstimateTime", false,
                 R"({"type":"estimate","t":2,"x_m":1,"y_m":1})" "\n"
                 R"({"type":"update","t":1,"sensor":"g","innovation":[1],"innovation_covariance":[1],"nis":1,"accepted":true})" "\n",
                 "est.ndjson:3: key 't': time goes backwards"},
        BadInput{"EstimateMajorVersion", false, R"({"type":"estimate_header","protocol":"rowloc-estimate/3.0"})" "\n",
                 "unsupported major version \"3\"", true}),
    [](const ::testing::TestParamInfo<BadInput>& param_info) { return std::string(param_info.param.name); });

}  // namespace
}  // namespace rowloc::formats
