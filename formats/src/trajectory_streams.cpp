// Readers of the truth and estimate NDJSON streams (see trajectory_streams.hpp).
#include "rowloc/formats/trajectory_streams.hpp"

#include "rowloc/formats/bounded_line_reader.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace rowloc::formats {
namespace {

using nlohmann::json;

/// Where we are: file and 1-based line; builds the error messages.
struct LineContext {
  const std::string& source;
  std::size_t line = 0;

  [[noreturn]] void Fail(const std::string& key, const std::string& reason) const {
    std::string where = source + ":" + std::to_string(line);
    if (!key.empty()) where += ": key '" + key + "'";
    throw StreamFormatError(where + ": " + reason);
  }
};

/// obj[key]; `prefix` + key names it in the message (nested objects).
const json& Require(const json& obj, const std::string& key, const LineContext& ctx, const std::string& prefix = "") {
  const auto it = obj.find(key);
  if (it == obj.end()) ctx.Fail(prefix + key, "missing required key");
  return *it;
}

double ToFiniteNumber(const json& value, const std::string& key, const LineContext& ctx) {
  if (!value.is_number()) ctx.Fail(key, "expected a number, got " + std::string(value.type_name()));
  const double v = value.get<double>();
  if (!std::isfinite(v)) ctx.Fail(key, "number is not finite");
  return v;
}

double RequireNumber(const json& obj, const std::string& key, const LineContext& ctx) {
  return ToFiniteNumber(Require(obj, key, ctx), key, ctx);
}

std::optional<double> OptionalNumber(const json& obj, const std::string& key, const LineContext& ctx,
                                     const std::string& prefix = "") {
  const auto it = obj.find(key);
  if (it == obj.end()) return std::nullopt;
  return ToFiniteNumber(*it, prefix + key, ctx);
}

bool RequireBool(const json& obj, const std::string& key, const LineContext& ctx) {
  const json& v = Require(obj, key, ctx);
  if (!v.is_boolean()) ctx.Fail(key, "expected a boolean, got " + std::string(v.type_name()));
  return v.get<bool>();
}

std::string RequireString(const json& obj, const std::string& key, const LineContext& ctx) {
  const json& v = Require(obj, key, ctx);
  if (!v.is_string()) ctx.Fail(key, "expected a string, got " + std::string(v.type_name()));
  return v.get<std::string>();
}

std::vector<double> NumberArray(const json& value, const std::string& key, const LineContext& ctx) {
  if (!value.is_array()) ctx.Fail(key, "expected an array, got " + std::string(value.type_name()));
  std::vector<double> out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    out.push_back(ToFiniteNumber(value[i], key + "[" + std::to_string(i) + "]", ctx));
  }
  return out;
}

enum class Definiteness { kPositive, kSemi };

/// Square matrix from n*n row-major numbers; must be symmetric and positive (semi-)definite.
Eigen::MatrixXd SymmetricMatrix(const std::vector<double>& v, Eigen::Index n, Definiteness definiteness,
                                const std::string& key, const LineContext& ctx) {
  Eigen::MatrixXd m(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    for (Eigen::Index c = 0; c < n; ++c) m(r, c) = v[static_cast<std::size_t>(r * n + c)];
  }
  const double scale = m.cwiseAbs().maxCoeff();
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) ctx.Fail(key, "matrix is not symmetric");
  if (definiteness == Definiteness::kSemi) {
    const double min_eigenvalue = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m, Eigen::EigenvaluesOnly)
                                      .eigenvalues()
                                      .minCoeff();
    if (min_eigenvalue < -1e-12 * scale) ctx.Fail(key, "matrix is not positive semi-definite");
  } else if (Eigen::LLT<Eigen::MatrixXd>(m).info() != Eigen::Success || scale == 0.0) {
    ctx.Fail(key, "matrix is not positive definite");
  }
  return m;
}

/// Per-wheel numbers: an object {name: number} (estimate "slip").
std::map<std::string, double> WheelNumbers(const json& value, const std::string& key,
                                           const LineContext& ctx) {
  if (!value.is_object()) ctx.Fail(key, "expected an object, got " + std::string(value.type_name()));
  std::map<std::string, double> out;
  for (const auto& [name, v] : value.items()) out[name] = ToFiniteNumber(v, key + "." + name, ctx);
  return out;
}

/// Truth "wheels": {name: {"slip": number, "rolling_radius_m": number > 0, ...}}; both are
/// optional per wheel.
void ParseTruthWheels(const json& value, const LineContext& ctx, TruthSample& out) {
  if (!value.is_object()) ctx.Fail("wheels", "expected an object, got " + std::string(value.type_name()));
  for (const auto& [name, wheel] : value.items()) {
    const std::string prefix = "wheels." + name + ".";
    if (!wheel.is_object()) ctx.Fail("wheels." + name, "expected an object");
    if (const auto slip = OptionalNumber(wheel, "slip", ctx, prefix)) out.wheel_slip[name] = *slip;
    if (const auto radius = OptionalNumber(wheel, "rolling_radius_m", ctx, prefix)) {
      if (*radius <= 0.0) ctx.Fail(prefix + "rolling_radius_m", "rolling radius must be > 0");
      out.wheel_rolling_radius_m[name] = *radius;
    }
  }
}

/// Estimate "wheel_calibration": {name: {rolling_radius_m, rolling_radius_sigma_m, slip_compliance,
/// slip_compliance_sigma}}, all required, each in its domain (kWheelCalibrationFields).
std::vector<WheelCalibrationRecord> WheelCalibration(const json& value, const LineContext& ctx) {
  const std::string key = "wheel_calibration";
  if (!value.is_object()) ctx.Fail(key, "expected an object, got " + std::string(value.type_name()));
  std::vector<WheelCalibrationRecord> out;
  for (const auto& [name, wheel] : value.items()) {  // nlohmann::json objects iterate sorted by key
    const std::string prefix = key + "." + name + ".";
    if (!wheel.is_object()) ctx.Fail(key + "." + name, "expected an object, got " + std::string(wheel.type_name()));
    WheelCalibrationRecord record{.wheel = name};
    for (const WheelCalibrationField& field : kWheelCalibrationFields) {
      const std::string path = prefix + field.key;
      const double v = ToFiniteNumber(Require(wheel, field.key, ctx, prefix), path, ctx);
      if (!field.InDomain(v)) ctx.Fail(path, field.DomainText());
      record.*field.member = v;
    }
    out.push_back(std::move(record));
  }
  return out;
}

/// Checks "protocol" = "<family>/<major>[.<anything>]" with major 1.
std::string CheckProtocol(const json& header, const std::string& family, const LineContext& ctx) {
  const std::string protocol = RequireString(header, "protocol", ctx);
  const std::string prefix = family + "/";
  if (protocol.rfind(prefix, 0) != 0) {
    ctx.Fail("protocol", "expected \"" + prefix + "1\", got \"" + protocol + "\"");
  }
  const std::string version = protocol.substr(prefix.size());
  const std::string major = version.substr(0, version.find('.'));
  if (major != "1") {
    ctx.Fail("protocol", "unsupported major version \"" + major + "\" (this reader knows " + prefix + "1)");
  }
  return protocol;
}

/// Iterates the non-blank lines of a stream as JSON objects: the callback gets (object, context).
/// A line longer than kMaxProtocolLineBytes is refused after its first kMaxProtocolLineBytes + 2
/// bytes (BoundedLineReader); the last line may lack its "\n".
template <typename OnLine>
void ForEachObject(std::istream& in, const std::string& source, const LineProgress& progress,
                   OnLine&& on_line) {
  std::string text;
  LineContext ctx{source, 0};
  BoundedLineReader lines(in, kMaxProtocolLineBytes);
  for (;;) {
    const BoundedLineReader::Result result = lines.Read(text);
    if (result == BoundedLineReader::Result::kEnd) return;
    if (result == BoundedLineReader::Result::kReadError) throw StreamFormatError(source + ": read error");
    ctx.line = lines.line_number();
    if (result == BoundedLineReader::Result::kTooLong) {
      ctx.Fail("", "line longer than 1 MiB (" + std::to_string(kMaxProtocolLineBytes) + " bytes, the protocol's limit)");
    }
    if (progress && ctx.line % kProgressLines == 0) progress(ctx.line);
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    json obj;
    try {
      obj = json::parse(text);
    } catch (const json::exception& e) {  // parse_error, or out_of_range for a number overflow
      ctx.Fail("", std::string("malformed JSON: ") + e.what());
    }
    if (!obj.is_object()) ctx.Fail("", "expected a JSON object");
    on_line(obj, ctx);
  }
}

/// The line rules of both streams: the first non-blank line is the header (type `header_type`,
/// protocol "<family>/1[...]"), and there is only one. Calls on_line(object, type, context) for every
/// other line and returns the header's protocol.
template <typename OnLine>
std::string ForEachRecord(std::istream& in, const std::string& source, const LineProgress& progress,
                          const std::string& header_type, const std::string& family, OnLine&& on_line) {
  std::string protocol;
  ForEachObject(in, source, progress, [&](const json& obj, const LineContext& ctx) {
    const std::string type = RequireString(obj, "type", ctx);
    if (protocol.empty()) {
      if (type != header_type) {
        ctx.Fail("type", "expected the \"" + header_type + "\" line first, got \"" + type + "\"");
      }
      protocol = CheckProtocol(obj, family, ctx);
    } else if (type == header_type) {
      ctx.Fail("type", "second \"" + header_type + "\"");
    } else {
      on_line(obj, type, ctx);
    }
  });
  if (protocol.empty()) throw StreamFormatError(source + ": empty stream (no " + header_type + " line)");
  return protocol;
}

/// Time check shared by both streams.
struct Clock {
  std::optional<double> last_t_s;
  double Advance(const json& obj, const LineContext& ctx) {
    const double t = RequireNumber(obj, "t", ctx);
    if (last_t_s && t < *last_t_s) {
      ctx.Fail("t", "time goes backwards (" + std::to_string(t) + " s after " + std::to_string(*last_t_s) + " s)");
    }
    last_t_s = t;
    return t;
  }
};

TruthSample ParseTruthLine(const json& obj, double t, const LineContext& ctx) {
  TruthSample s;
  s.t_s = t;
  s.position_m = {RequireNumber(obj, "x_m", ctx), RequireNumber(obj, "y_m", ctx)};
  s.phi_rad = RequireNumber(obj, "phi_rad", ctx);
  s.gnss_available = RequireBool(obj, "gnss_available", ctx);
  if (const auto it = obj.find("wheels"); it != obj.end()) ParseTruthWheels(*it, ctx, s);
  s.line = ctx.line;
  return s;
}

EstimateSample ParseEstimateLine(const json& obj, double t, const LineContext& ctx) {
  EstimateSample s;
  s.t_s = t;
  s.position_m = {RequireNumber(obj, "x_m", ctx), RequireNumber(obj, "y_m", ctx)};
  s.phi_rad = OptionalNumber(obj, "phi_rad", ctx);
  if (const auto it = obj.find("covariance_xy_phi"); it != obj.end()) {
    const std::vector<double> v = NumberArray(*it, "covariance_xy_phi", ctx);
    if (v.size() != 9 && v.size() != 4) {
      ctx.Fail("covariance_xy_phi", "expected 9 (3x3) or 4 (2x2) numbers, got " + std::to_string(v.size()));
    }
    s.covariance = SymmetricMatrix(v, v.size() == 9 ? 3 : 2, Definiteness::kSemi, "covariance_xy_phi", ctx);
  }
  if (const auto it = obj.find("slip"); it != obj.end()) s.wheel_slip = WheelNumbers(*it, "slip", ctx);
  if (const auto it = obj.find("wheel_calibration"); it != obj.end()) s.wheel_calibration = WheelCalibration(*it, ctx);
  s.line = ctx.line;
  return s;
}

UpdateRecord ParseUpdateLine(const json& obj, double t, const LineContext& ctx) {
  UpdateRecord u;
  u.t_s = t;
  u.sensor = RequireString(obj, "sensor", ctx);
  const std::vector<double> nu = NumberArray(Require(obj, "innovation", ctx), "innovation", ctx);
  if (nu.empty()) ctx.Fail("innovation", "empty innovation");
  u.innovation = Eigen::Map<const Eigen::VectorXd>(nu.data(), static_cast<Eigen::Index>(nu.size()));
  const std::vector<double> s =
      NumberArray(Require(obj, "innovation_covariance", ctx), "innovation_covariance", ctx);
  if (s.size() != nu.size() * nu.size()) {
    ctx.Fail("innovation_covariance", "expected " + std::to_string(nu.size() * nu.size()) +
                                          " numbers for an innovation of length " + std::to_string(nu.size()) +
                                          ", got " + std::to_string(s.size()));
  }
  u.innovation_covariance =
      SymmetricMatrix(s, u.innovation.size(), Definiteness::kPositive, "innovation_covariance", ctx);
  u.nis = RequireNumber(obj, "nis", ctx);
  u.accepted = RequireBool(obj, "accepted", ctx);
  u.line = ctx.line;
  return u;
}

}  // namespace

TruthStream ParseTruthStream(std::istream& in, const std::string& source_name, const LineProgress& progress) {
  TruthStream out;
  out.source_name = source_name;
  Clock clock;
  out.protocol = ForEachRecord(in, source_name, progress, "truth_header", "rowloc-truth",
                               [&](const json& obj, const std::string& type, const LineContext& ctx) {
                                 if (type == "truth") {
                                   out.samples.push_back(ParseTruthLine(obj, clock.Advance(obj, ctx), ctx));
                                 } else {
                                   ++out.skipped_lines;
                                 }
                               });
  return out;
}

EstimateStream ParseEstimateStream(std::istream& in, const std::string& source_name,
                                   const LineProgress& progress) {
  EstimateStream out;
  out.source_name = source_name;
  Clock clock;
  out.protocol = ForEachRecord(in, source_name, progress, "estimate_header", "rowloc-estimate",
                               [&](const json& obj, const std::string& type, const LineContext& ctx) {
                                 if (type == "estimate") {
                                   out.estimates.push_back(ParseEstimateLine(obj, clock.Advance(obj, ctx), ctx));
                                 } else if (type == "update") {
                                   out.updates.push_back(ParseUpdateLine(obj, clock.Advance(obj, ctx), ctx));
                                 } else {
                                   ++out.skipped_lines;
                                 }
                               });
  return out;
}

namespace {
std::ifstream OpenOrThrow(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw StreamFormatError(path.string() + ": cannot open file");
  return in;
}
}  // namespace

TruthStream ReadTruthStream(const std::filesystem::path& path, const LineProgress& progress) {
  std::ifstream in = OpenOrThrow(path);
  return ParseTruthStream(in, path.string(), progress);
}

EstimateStream ReadEstimateStream(const std::filesystem::path& path, const LineProgress& progress) {
  std::ifstream in = OpenOrThrow(path);
  return ParseEstimateStream(in, path.string(), progress);
}

}  // namespace rowloc::formats
