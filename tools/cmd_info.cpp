// quadrix info FILE: counts per kind, bounding box, metadata, validation result; for a volume its
// statistics (tools/info_volume.h), for a mesh or point cloud its counts and bounds.
#include <iostream>
#include <map>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "core/mesh_io.h"
#include "core/model_io.h"
#include "tools/cli.h"
#include "tools/info_volume.h"
#include "tools/scene_input.h"

namespace quadrix::cli {
namespace {

nlohmann::json box_json(const Box3& box) {
  return {{"min", {box.min.x(), box.min.y(), box.min.z()}},
          {"max", {box.max.x(), box.max.y(), box.max.z()}},
          {"diagonal", box.diagonal()}};
}

std::string box_line(const Box3& box) {
  return fmt::format("  bounding box       [{:.6g} {:.6g} {:.6g}] – [{:.6g} {:.6g} {:.6g}], diagonal {:.6g}\n", box.min.x(),
                     box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z(), box.diagonal());
}

// A mesh file (PLY with faces, OFF, OBJ, STL): vertices, faces by size, colours, bounding box.
ExitCode info_mesh(const std::string& file, const PolygonMesh& mesh, bool json, Report& report) {
  std::size_t triangles = 0, quads = 0, larger = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::size_t n = mesh.face(f).size();
    (n == 3 ? triangles : n == 4 ? quads : larger) += 1;
  }
  Box3 box;
  for (const auto& v : mesh.vertices) box.extend(v);
  const char* what = triangles == mesh.face_count() ? "triangle mesh" : "polygon mesh";
  nlohmann::json j = {{"file", file},
                      {"valid", true},
                      {"kind", "mesh"},
                      {"vertices", mesh.vertices.size()},
                      {"faces", mesh.face_count()},
                      {"face_sizes", {{"triangles", triangles}, {"quads", quads}, {"larger", larger}}},
                      {"vertex_colours", !mesh.colours.empty()},
                      {"bbox", box_json(box)}};
  report.json["info"] = j;
  if (json) {
    std::cout << j.dump(2) << "\n";
    return kOk;
  }
  std::cout << fmt::format("{}: a {} (render and view draw it as flat triangles)\n", file, what);
  std::cout << fmt::format("  vertices           {}{}\n", mesh.vertices.size(), mesh.colours.empty() ? "" : ", with colours");
  std::cout << fmt::format("  faces              {} (triangles {}, quads {}, larger {})\n", mesh.face_count(), triangles,
                           quads, larger);
  std::cout << box_line(box);
  return kOk;
}

// A point cloud (XYZ, PTS, a PLY without faces): points, normals, bounding box.
ExitCode info_points(const std::string& file, const PointCloud& cloud, bool json, Report& report) {
  Box3 box;
  for (const auto& p : cloud.points) box.extend(p);
  nlohmann::json j = {{"file", file},           {"valid", true},         {"kind", "points"},
                      {"points", cloud.points.size()}, {"normals", cloud.has_normals()}, {"bbox", box_json(box)}};
  report.json["info"] = j;
  if (json) {
    std::cout << j.dump(2) << "\n";
    return kOk;
  }
  std::cout << fmt::format("{}: a point cloud (fit reads it; render draws it over a model with --points)\n", file);
  std::cout << fmt::format("  points             {}{}\n", cloud.points.size(), cloud.has_normals() ? ", with normals" : "");
  std::cout << box_line(box);
  return kOk;
}

// A molecule (PDB, mmCIF): atoms, chains, residues, elements, bonds, bounding box in Å.
ExitCode info_molecule(const std::string& file, bool json, Report& report) {
  const Molecule mol = read_molecule(file);
  const std::vector<Bond> bonds = molecule_bonds(mol);
  std::set<std::string> chains;
  std::set<std::tuple<std::string, int, std::string>> residues;
  std::map<std::string, std::size_t> elements;
  Box3 box;
  for (const Atom& a : mol.atoms) {
    chains.insert(a.chain);
    residues.insert({a.chain, a.residue_number, a.residue});
    ++elements[a.element];
    box.extend(a.position);
  }
  nlohmann::json j = {{"file", file},
                      {"valid", true},
                      {"kind", "molecule"},
                      {"name", mol.name},
                      {"atoms", mol.atoms.size()},
                      {"chains", chains.size()},
                      {"residues", residues.size()},
                      {"elements", elements},
                      {"bonds", bonds.size()},
                      {"file_bonds", mol.file_bonds.size()},
                      {"alternates_left_out", mol.alternates_left_out},
                      {"bbox", box_json(box)}};
  report.json["info"] = j;
  if (json) {
    std::cout << j.dump(2) << "\n";
    return kOk;
  }
  std::cout << fmt::format("{}: molecule {} (render and view draw it as glyphs; convert glyphs or skin make a model)\n",
                           file, mol.name);
  std::cout << fmt::format("  atoms              {}{}\n", mol.atoms.size(),
                           mol.alternates_left_out ? fmt::format(" ({} alternate locations left out)", mol.alternates_left_out) : "");
  std::cout << fmt::format("  chains             {}\n", chains.size());
  std::cout << fmt::format("  residues           {}\n", residues.size());
  std::string list;
  for (const auto& [e, n] : elements) list += fmt::format("{}{} {}", list.empty() ? "" : ", ", e, n);
  std::cout << fmt::format("  elements           {}\n", list);
  std::cout << fmt::format("  bonds              {} ({} stated by the file)\n", bonds.size(), mol.file_bonds.size());
  std::cout << box_line(box);
  return kOk;
}

}  // namespace

void add_info(CLI::App& root, Commands& commands) {
  auto* app = root.add_subcommand("info", "Validate a .qxm/.slim2t model and print what it holds; for a volume, its "
                                          "values and suggested iso-values; for a mesh, point cloud or molecule, its counts "
                                          "and bounds");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto raw = std::make_shared<RawVolumeArgs>();
  app->add_option("MODEL", *file, "Model file (.qxm or .slim2t), or a volume (.nhdr/.nrrd, .inr[.gz], raw with --dims "
                                  "and --type): range, percentiles, histogram, suggested iso-values; or a mesh "
                                  "(.ply/.obj/.off/.stl: vertices, faces, bounds), point cloud (.xyz/.pts, a .ply "
                                  "without faces) or molecule (.pdb/.ent/.cif/.mmcif, optionally .gz: atoms, chains, "
                                  "residues, elements, bonds)")->required();
  app->add_flag("--json", *json, "Print the summary as JSON on stdout");
  app->add_option("--dims", raw->dims, "Raw volume: samples per axis X,Y,Z (x fastest)");
  app->add_option("--type", raw->type, "Raw volume: uint8|int8|uint16|int16|uint32|int32|float|double");
  app->add_flag("--big-endian", raw->big_endian, "Raw volume: big-endian samples (default little)");
  app->add_option("--spacing", raw->spacing, "Raw volume: voxel spacing SX,SY,SZ (default 1,1,1)");
  app->add_option("--header-bytes", raw->header_bytes, "Raw volume: bytes to skip at the start of the file")->check(non_negative());
  commands.push_back({app, [file, json, raw](const CommonOptions&, Report& report) {
                        Model m;
                        try {
                          if (is_volume_file(*file, *raw)) return run_info_volume(*file, *raw, *json, report);
                          // A mesh or a point cloud: what it is, rather than what a model reader finds wrong with it.
                          if (is_molecule_file(*file)) return info_molecule(*file, *json, report);
                          if (detect_file_kind(*file) == FileKind::mesh) return info_mesh(*file, read_mesh(*file), *json, report);
                          if (is_point_cloud_file(*file)) return info_points(*file, read_points(*file), *json, report);
                          m = read_model(*file);  // validates; throws FormatError
                        } catch (const std::exception& e) {
                          // --json: a script reading stdout learns why too (the exit code is main's).
                          if (*json)
                            std::cout << nlohmann::json{{"file", *file}, {"valid", false}, {"error", e.what()}}.dump(2)
                                      << "\n";
                          throw;
                        }
                        const Box3 box = bounds(m);
                        nlohmann::json j;
                        j["file"] = *file;
                        j["valid"] = true;
                        j["kind"] = "model";
                        j["counts"] = {{"slim", m.slims.size()}, {"tet", m.tets.size()}, {"glyph", m.glyphs.size()},
                                       {"implicit", m.implicits.size()}};
                        std::size_t g[3] = {0, 0, 0};
                        for (const auto& gl : m.glyphs) ++g[static_cast<int>(gl.kind)];
                        j["glyph_kinds"] = {{"sphere", g[0]}, {"ellipsoid", g[1]}, {"cylinder", g[2]}};
                        if (!box.empty()) j["bbox"] = box_json(box);
                        const bool hierarchical = !m.slim_hierarchy.empty();
                        SlimHierarchyStats hs;
                        if (hierarchical) {
                          hs = slim_hierarchy_stats(m);
                          j["slim_hierarchy"] = {{"balls", m.slim_hierarchy.size()},
                                                 {"levels", hs.levels},
                                                 {"leaves", hs.leaves},
                                                 {"interior", hs.interior},
                                                 {"roots", hs.roots},
                                                 {"error", {{"min", hs.min_error}, {"max", hs.max_error}}}};
                        }
                        if (!m.implicits.empty()) {
                          j["implicits"] = nlohmann::json::array();
                          for (const auto& s : m.implicits)
                            j["implicits"].push_back(
                                {{"expression", s.expression},
                                 {"parameters", s.parameters},
                                 {"bounds", {{"min", {s.bounds.min.x(), s.bounds.min.y(), s.bounds.min.z()}},
                                             {"max", {s.bounds.max.x(), s.bounds.max.y(), s.bounds.max.z()}}}}});
                        }
                        j["metadata"] = m.metadata;
                        report.json["info"] = j;
                        if (*json) {
                          std::cout << j.dump(2) << "\n";
                          return kOk;
                        }
                        std::cout << fmt::format("{}: valid\n", *file);
                        std::cout << fmt::format("  slim patches       {}\n", m.slims.size());
                        std::cout << fmt::format("  tetrahedron patches {}\n", m.tets.size());
                        std::cout << fmt::format("  glyphs             {} (spheres {}, ellipsoids {}, cylinders {})\n",
                                                 m.glyphs.size(), g[0], g[1], g[2]);
                        if (!m.implicits.empty()) {
                          std::cout << fmt::format("  implicit surfaces  {}\n", m.implicits.size());
                          for (const auto& s : m.implicits) {
                            std::string params;
                            for (const auto& [k, v] : s.parameters) params += fmt::format(" {}={:.17g}", k, v);
                            const std::string e = s.expression.size() > 60 ? s.expression.substr(0, 57) + "..." : s.expression;
                            std::cout << fmt::format("    {}{} in [{:.6g} {:.6g} {:.6g}] – [{:.6g} {:.6g} {:.6g}]\n", e,
                                                     params, s.bounds.min.x(), s.bounds.min.y(), s.bounds.min.z(),
                                                     s.bounds.max.x(), s.bounds.max.y(), s.bounds.max.z());
                          }
                        }
                        if (hierarchical)
                          std::cout << fmt::format("  slim hierarchy     {} balls: {} levels, {} leaves, {} interior, "
                                                   "{} roots; error {:.6g} – {:.6g}\n",
                                                   m.slim_hierarchy.size(), hs.levels, hs.leaves, hs.interior,
                                                   hs.roots, hs.min_error, hs.max_error);
                        if (!box.empty()) std::cout << box_line(box);
                        for (const auto& [k, v] : m.metadata) std::cout << fmt::format("  {:<18} {}\n", k, v);
                        return kOk;
                      }});
}

}  // namespace quadrix::cli
