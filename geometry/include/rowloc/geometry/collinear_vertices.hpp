// Dropping collinear vertices of a row: a vertex that lies within a tolerance of the straight
// segment joining its neighbours that are kept carries no geometry, but it costs: every segment is
// an entry of the SegmentIndex, and a sensor cone that sweeps a dense straight row casts against
// every one of them (a row of 10^4 vertices along a 50 m lane: 130 segments per echo instead of 1;
// issue 26 measured 2.7 s of replay for 10^4 vertices, 193 s for 10^5).
//
// Method: sleeve fitting (Zhao and Saalfeld 1997), linear in the vertex count. From the last kept
// vertex a, each following vertex p_k at distance d_k > tol admits the directions within
// asin(tol / d_k) of its own; the intersection of these wedges holds exactly the directions of the
// lines through a that pass within tol of every vertex seen. Vertex p_j ends the current chord when
// its direction leaves the wedge of the vertices before it, or when it is no farther from a than
// the previous one (the row turns back: never simplified, so that such a row is still refused by
// RowOutlineDefect); the vertex before it is then kept and becomes a. Every dropped vertex lies
// within tol of the chord that replaces it; the first and last vertices are always kept (for a
// closed row the first vertex is both, so the ring's shape is kept within tol too).
#pragma once

#include <Eigen/Core>

#include <vector>

namespace rowloc::geometry {

/// The vertices of a polyline (closed: a ring without its repeated vertex) without those within
/// tolerance_m of the chord of their kept neighbours (see above). tolerance_m >= 0; 0 keeps all but
/// exactly collinear vertices between their neighbours. Order and kept vertices are unchanged.
std::vector<Eigen::Vector2d> DropCollinearVertices(const std::vector<Eigen::Vector2d>& points, bool closed,
                                                   double tolerance_m);

}  // namespace rowloc::geometry
