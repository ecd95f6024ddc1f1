#pragma once
/// What `render` and `view` draw from their MODEL and --mesh arguments, read by one function so
/// both commands open the same files. MODEL by kind:
///   .qxm (any PLY encoding of the profile), Kanai's .slim2t  → a model (core/model_io.h);
///   PDB or mmCIF (.pdb .ent .cif .mmcif, optionally .gz)     → glyphs, converted here in the
///       given --style and --colour-by element|chain|residue (convert/molecule_glyphs.h);
///   a mesh: PLY with faces, OFF, OBJ, STL                    → flat triangles (core/io/io.h).
/// A point cloud as MODEL is refused (render draws one over a model with --points).
#include <optional>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/mesh_io.h"
#include "core/model.h"

namespace quadrix::cli {

/// The command-line arguments that name what to draw.
struct SceneFiles {
  std::string model;      ///< MODEL; empty when the command draws only implicit surfaces
  std::string mesh;       ///< --mesh, drawn beside the model; empty: none
  std::string style;      ///< --style spacefill|balls-sticks|licorice; empty: by atom count
  std::string colour_by;  ///< --colour-by element|chain|residue; empty: element
};

/// What MODEL turned out to be.
enum class SceneInputKind { none, model, molecule, mesh };

struct Scene {
  Model model;                      ///< primitives to ray-cast (empty for a mesh MODEL)
  std::optional<PolygonMesh> mesh;  ///< a mesh MODEL, or --mesh
  SceneInputKind kind = SceneInputKind::none;
};

/// "none", "model", "molecule" or "mesh" (reports).
const char* scene_input_name(SceneInputKind kind);

/// Adds --style spacefill|balls-sticks|licorice (a molecule MODEL's glyphs, as `convert glyphs`;
/// unset: by atom count) to `render` or `view`.
void add_molecule_style_option(CLI::App& app, std::string& style);

/// True for the --colour-by values that colour a molecule's atoms: element, chain, residue.
bool is_atom_colouring(std::string_view colour_by);

/// A molecule scene's report entry: style, colour_by, atoms and bonds, from the glyphs' metadata.
nlohmann::json molecule_json(const Model& glyphs);

/// True for a file read as points: a point-cloud format (.xyz .txt .pts, or a PLY without faces;
/// core/io/io.h known_file_kind). A file no format claims is not taken for points, so the model
/// reader names what is wrong with it instead.
/// \throws IoError when it cannot be read.
bool is_point_cloud_file(const std::string& file);

/// Reads MODEL by its kind (the list above) and --mesh.
/// \throws CLI::ValidationError (exit 2) for --style or --colour-by element|chain|residue when
///         MODEL is not a molecule file, naming the option and the file; InvalidInput for a mesh
///         both as MODEL and --mesh, or a point cloud as MODEL; what the readers throw.
Scene read_scene(const SceneFiles& files);

}  // namespace quadrix::cli
