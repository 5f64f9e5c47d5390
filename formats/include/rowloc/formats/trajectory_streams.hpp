// Readers of the ground-truth stream and the estimate stream (docs/protocol.md §2 and §3): the
// two NDJSON files `rowloc evaluate` compares.
//
// Rules (docs/protocol.md, introduction): the first non-blank line is the header
// (`truth_header` with protocol "rowloc-truth/<major>[.<minor>]", or `estimate_header` with
// "rowloc-estimate/<major>[...]"); only major version 1 is accepted. Unknown keys are ignored;
// lines of an unknown `type` are skipped and counted (never silently: the count is returned).
// Blank lines are skipped; the last line may lack its "\n". A line longer than 1 MiB
// (kMaxProtocolLineBytes) is refused once its first 1 MiB + 2 bytes are read, never held whole
// (bounded_line_reader.hpp). Every other defect is a StreamFormatError whose message names the
// file, the 1-based line number and the key: malformed JSON, a missing required key, a wrong
// type, a non-finite number, a truth rolling radius <= 0, a `wheel_calibration` entry out of its
// domain (R_w <= 0, negative kappa or sigma), an estimate covariance that is not symmetric positive semi-definite
// (singular ones, e.g. a known initial pose, are allowed), an innovation covariance S that is not
// symmetric positive definite, or a time `t`
// smaller than the previous line's (time never decreases within one stream; in the estimate
// stream `estimate` and `update` lines share one clock).
//
// Covariances are stored as read (row-major in the file, Eigen matrices here). Symmetry is
// checked to a relative tolerance of 1e-9 of the largest entry; semi-definiteness by the smallest
// eigenvalue (>= -1e-12 of the largest entry), definiteness by a successful Eigen LLT. Angles are taken as written (a reader does not re-wrap them).
#pragma once

#include "rowloc/formats/wheel_calibration_record.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <istream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rowloc::formats {

/// A defect in a truth or estimate stream; the message names file, line and key.
class StreamFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One `truth` line: what the evaluator needs of docs/protocol.md §2.
struct TruthSample {
  double t_s = 0.0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< reference point, local ENU
  double phi_rad = 0.0;                                  ///< heading from +East, CCW
  bool gnss_available = true;
  std::map<std::string, double> wheel_slip;              ///< wheel name -> SAE slip (if given)
  /// wheel name -> true rolling radius R_a, m (> 0; if given; `wheels.<name>.rolling_radius_m`)
  std::map<std::string, double> wheel_rolling_radius_m;
  std::size_t line = 0;                                  ///< 1-based line in the file
};

struct TruthStream {
  std::string source_name;        ///< file name (for messages)
  std::string protocol;           ///< header "protocol" as written
  std::vector<TruthSample> samples;  ///< non-decreasing t_s
  std::size_t skipped_lines = 0;  ///< lines of an unknown "type"
};

/// One `estimate` line (docs/protocol.md §3).
struct EstimateSample {
  double t_s = 0.0;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  std::optional<double> phi_rad;
  /// Covariance of (x, y, phi) (3x3) or of (x, y) (2x2), m^2 / m rad / rad^2; symmetric PSD.
  std::optional<Eigen::MatrixXd> covariance;
  std::map<std::string, double> wheel_slip;
  /// `wheel_calibration`, sorted by wheel name: every entry has all four numbers, finite, with
  /// R_w > 0 and kappa and both sigmas >= 0 (else a StreamFormatError).
  std::vector<WheelCalibrationRecord> wheel_calibration;
  std::size_t line = 0;
};

/// One `update` line: a measurement update of the filter.
struct UpdateRecord {
  double t_s = 0.0;
  std::string sensor;
  Eigen::VectorXd innovation;             ///< length m >= 1
  Eigen::MatrixXd innovation_covariance;  ///< S, m x m, SPD
  double nis = 0.0;                       ///< as recorded by the filter
  bool accepted = true;                   ///< passed the gate
  std::size_t line = 0;
};

struct EstimateStream {
  std::string source_name;
  std::string protocol;
  std::vector<EstimateSample> estimates;  ///< non-decreasing t_s
  std::vector<UpdateRecord> updates;      ///< non-decreasing t_s
  std::size_t skipped_lines = 0;
};

/// Called with the number of lines read so far, every kProgressLines lines.
using LineProgress = std::function<void(std::size_t lines_read)>;
inline constexpr std::size_t kProgressLines = 100000;

/// Parse from a stream; source_name is used in messages. Throw StreamFormatError.
TruthStream ParseTruthStream(std::istream& in, const std::string& source_name,
                             const LineProgress& progress = {});
EstimateStream ParseEstimateStream(std::istream& in, const std::string& source_name,
                                   const LineProgress& progress = {});

/// Read a file; a file that cannot be opened is a StreamFormatError too.
TruthStream ReadTruthStream(const std::filesystem::path& path, const LineProgress& progress = {});
EstimateStream ReadEstimateStream(const std::filesystem::path& path,
                                  const LineProgress& progress = {});

}  // namespace rowloc::formats
