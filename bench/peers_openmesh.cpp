// OpenMesh peer: quadric-error decimation bounded by a Hausdorff tolerance.
#include "bench/peers.h"

#include <chrono>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModHausdorffT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <fmt/format.h>

#include "core/error.h"

namespace quadrix::peers {
namespace {

struct Traits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

}  // namespace

Decimation decimate_quadric(const PolygonMesh& input, double max_error) {
  if (input.face_count() == 0) throw InvalidInput("decimate_quadric: the mesh has no faces");
  if (!(max_error > 0)) throw InvalidInput(fmt::format("decimate_quadric: tolerance must be positive, got {}", max_error));
  Decimation out;
  const auto t0 = std::chrono::steady_clock::now();
  TriMesh mesh;
  std::vector<TriMesh::VertexHandle> handles;
  handles.reserve(input.vertices.size());
  for (const auto& p : input.vertices) handles.push_back(mesh.add_vertex({p.x(), p.y(), p.z()}));
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    const auto vs = input.face(f);
    for (std::size_t k = 1; k + 1 < vs.size(); ++k)
      if (!mesh.add_face(handles[vs[0]], handles[vs[k]], handles[vs[k + 1]]).is_valid()) ++out.skipped_faces;
  }
  {
    OpenMesh::Decimater::DecimaterT<TriMesh> decimater(mesh);
    OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle quadric;
    OpenMesh::Decimater::ModHausdorffT<TriMesh>::Handle hausdorff;
    decimater.add(quadric);
    decimater.add(hausdorff);
    decimater.module(quadric).unset_max_err();  // priority only
    decimater.module(hausdorff).set_tolerance(max_error);
    decimater.initialize();
    decimater.decimate_to(0);  // while any collapse is legal
    mesh.garbage_collection();  // needs the status the decimater releases when destroyed
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    out.mesh.vertices.emplace_back(p[0], p[1], p[2]);
  }
  for (const auto f : mesh.faces()) {
    std::vector<int> ids;
    for (const auto v : mesh.fv_range(f)) ids.push_back(v.idx());
    out.mesh.add_face(ids);
  }
  return out;
}

}  // namespace quadrix::peers
