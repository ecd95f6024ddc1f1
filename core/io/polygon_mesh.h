#pragma once
/// A polygon mesh as a face soup: triangles, quads and mixed polygons kept as in the file.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace quadrix {

/// Faces in compressed form: face f has the vertex indices
/// indices[offsets[f] .. offsets[f+1]), counter-clockwise seen from outside.
struct PolygonMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<int> indices;
  std::vector<int> offsets{0};
  /// Optional 8-bit sRGB colour per vertex: empty, or one per vertex (PLY red/green/blue,
  /// OFF's COFF columns, OBJ's "v x y z r g b").
  std::vector<std::array<std::uint8_t, 3>> colours;
  /// Optional unit normal per vertex: empty, or one per vertex (PLY nx/ny/nz, OFF's NOFF
  /// columns, OBJ's "vn"); what smooth shading uses in other programs.
  std::vector<Eigen::Vector3d> normals;

  std::size_t face_count() const { return offsets.size() - 1; }
  std::span<const int> face(std::size_t f) const {
    return {indices.data() + offsets[f], static_cast<std::size_t>(offsets[f + 1] - offsets[f])};
  }
  void add_face(std::span<const int> vs) {
    indices.insert(indices.end(), vs.begin(), vs.end());
    offsets.push_back(static_cast<int>(indices.size()));
  }
  /// Drops the vertices no face uses (and their colours and normals), renumbering the faces;
  /// returns how many.
  std::size_t remove_unused_vertices() {
    std::vector<int> id(vertices.size(), -1);
    for (const int v : indices) id[static_cast<std::size_t>(v)] = 0;
    std::size_t n = 0;
    for (std::size_t v = 0; v < vertices.size(); ++v)
      if (id[v] == 0) {
        id[v] = static_cast<int>(n);
        vertices[n] = vertices[v];
        if (!colours.empty()) colours[n] = colours[v];
        if (!normals.empty()) normals[n] = normals[v];
        ++n;
      }
    const std::size_t removed = vertices.size() - n;
    vertices.resize(n);
    if (!colours.empty()) colours.resize(n);
    if (!normals.empty()) normals.resize(n);
    for (int& v : indices) v = id[static_cast<std::size_t>(v)];
    return removed;
  }
  /// Whether every face is a triangle.
  bool is_triangles() const {
    for (std::size_t f = 0; f < face_count(); ++f)
      if (offsets[f + 1] - offsets[f] != 3) return false;
    return true;
  }
  /// The same vertices with each face split into the fan of triangles from its first vertex
  /// (the triangles every reader of faces in Quadrix takes as the face's surface).
  PolygonMesh fanned() const {
    PolygonMesh m;
    m.vertices = vertices;
    m.colours = colours;
    m.normals = normals;
    for (std::size_t f = 0; f < face_count(); ++f) {
      const auto vs = face(f);
      for (std::size_t k = 1; k + 1 < vs.size(); ++k) m.add_face(std::array<int, 3>{vs[0], vs[k], vs[k + 1]});
    }
    return m;
  }
};

}  // namespace quadrix
