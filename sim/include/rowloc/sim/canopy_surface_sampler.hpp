// CanopySurfaceSampler: a synthetic survey point cloud of a RowWorld (the design: "A synthetic survey
// generator produces point clouds of the same world for the mapping pipeline"; issue 3, "World").
// Documented in docs/simulation-world.md, "Outputs: row map, survey cloud, OctoMap".
//
// Surfaces (row_world.hpp notation: station s, row centre m_k(s), left normal n(s), half-widths
// w_L, w_R, band [b_k(s), t_k(s)] above the terrain z = T(x, y); every point is evaluated with
// RowWorld's and TerrainSurface's own functions, so a noise-free point lies on the exact solid):
// - left / right face:  xy = m_k(s) + w_L(s) n(s)  /  m_k(s) - w_R(s) n(s),
//                       z  = T(xy) + h, h in [b_k(s), t_k(s)]; outward normal horizontal,
//                       perpendicular to the face curve (+n side for the left face);
// - top:                xy = m_k(s) + u n(s), u in [-w_R(s), w_L(s)], z = T(xy) + t_k(s);
//                       normal = (P_s x P_u) / |P_s x P_u| (upward);
// - end caps, at both ends of every run of stations with canopy (row ends and gap ends):
//                       xy = m_k(s_e) + u n(s_e), z = T(xy) + h, h in the band; normal -+ tangent;
// - optionally the terrain not covered by canopy, laterally from half a spacing right of row 0 to
//   half a spacing left of the last row, stations [0, L]: xy = c(s) + e n(s), z = T(xy), normal
//   (-dT/dx, -dT/dy, 1) / norm. (The underside of the canopy is not sampled: neither a drone nor a
//   lane-driving LiDAR sees it well.)
// Sampling is stratified ("jittered grid") in each surface's parameters, with cell size `spacing`:
// along a curve, cell j covers arc length [j h, (j + 1) h) of that curve (the face curve for the
// faces, the row centre for the top and end caps, the offset curve for a terrain strip), measured by
// chords at a fine station step <= h / 4 that keeps the chords within 0.1 mm of the curve; across
// (height on faces and end caps, u on the top, e on the terrain) likewise; each cell holds one
// point at a uniform position and points beyond the surface's end are discarded, so the expected
// number of points is (area measured in those parameters) / h^2 exactly, and no point falls inside
// a gap (gaps are open station intervals; a run [a, b] of canopy is sampled on [a, b)).
// Noise: each kept point moves by sigma * N(0, 1) along its unit normal; then it is dropped with
// probability `dropout_fraction`. Randomness: positions from std::mt19937_64(seed), noise and
// dropout from a second std::mt19937_64(seed ^ 0x5DEECE66DA3B2C1F) that draws one uniform and one
// Box-Muller normal (two uniforms) per point whatever sigma and dropout are, so clouds of the same
// seed differ only by their noise and dropout. Uniforms use the engine's raw output (portable).
// Scan defects (map build robustness, docs/mapping.md): `one_sided` leaves out every right face
// (a mobile scanner that saw each row from one side); `outlier_fraction` f adds, after the rows
// and the terrain, round(f N) points (N = the points kept so far) uniform in the kept points'
// bounding box grown by 1 m on every side (below the ground too: the worst case for a DTM), from
// a third std::mt19937_64(seed ^ 0x2545F4914F6CDD1D); they are SurveySurface::kOutlier, row -1.
#pragma once

#include "rowloc/sim/row_world.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace rowloc::sim {

struct SurveyParams {
  double spacing_m = 0.05;           ///< canopy cell size h, in [0.001, 10] m
  double noise_sigma_m = 0.005;      ///< sigma of the noise along the normal, in [0, 1] m
  double dropout_fraction = 0.0;     ///< probability that a point is dropped, in [0, 1)
  bool include_terrain = false;      ///< also sample the terrain not covered by canopy
  double terrain_spacing_m = 0.1;    ///< terrain cell size, in [0.001, 100] m
  bool one_sided = false;           ///< leave out the right faces of every row
  double outlier_fraction = 0.0;    ///< outliers added, as a fraction of the kept points, in [0, 0.5]
  std::uint64_t seed = 1;
};

/// The largest number of points a survey may produce (about 1.2 GB of positions).
inline constexpr double kMaxSurveyPoints = 5e7;

enum class SurveySurface { kLeftFace, kRightFace, kTop, kEndCap, kTerrain, kOutlier };

/// One survey point with what produced it (for tests and for labelled clouds).
struct SurveySample {
  Eigen::Vector3d position_m;          ///< noisy point, world ENU metres (z absolute)
  Eigen::Vector3d normal;              ///< outward unit normal of the surface at the noise-free point
  double noise_m = 0.0;                ///< the offset applied along the normal
  SurveySurface surface = SurveySurface::kTop;
  int row = -1;                        ///< 0-based row, -1 for terrain
  double station_m = 0.0;              ///< station s of the noise-free point
};

/// Why the parameters are unusable (naming the field), or nullopt.
std::optional<std::string> SurveyParamsProblem(const SurveyParams& params);

/// An upper bound of the number of points SampleSurvey can produce (before dropout).
/// Throws std::invalid_argument on bad parameters (SurveyParamsProblem).
double SurveyPointBound(const RowWorld& world, const SurveyParams& params);

/// Calls `visit` for every kept sample, rows in order, then the terrain. Deterministic.
/// Throws std::invalid_argument on bad parameters, or if SurveyPointBound exceeds kMaxSurveyPoints
/// (the message gives the bound and suggests a larger spacing).
void SampleSurvey(const RowWorld& world, const SurveyParams& params,
                  const std::function<void(const SurveySample&)>& visit);

/// The positions of SampleSurvey's samples.
std::vector<Eigen::Vector3d> SampleCanopySurface(const RowWorld& world, const SurveyParams& params);

}  // namespace rowloc::sim
