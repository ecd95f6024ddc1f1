#include "tools/scene_input.h"

#include <utility>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "convert/molecule_glyphs.h"
#include "core/error.h"
#include "core/model_io.h"

namespace quadrix::cli {

const char* scene_input_name(SceneInputKind kind) {
  switch (kind) {
    case SceneInputKind::model: return "model";
    case SceneInputKind::molecule: return "molecule";
    case SceneInputKind::mesh: return "mesh";
    case SceneInputKind::none: break;
  }
  return "none";
}

void add_molecule_style_option(CLI::App& app, std::string& style) {
  app.add_option("--style", style, "A molecule MODEL's glyphs: spacefill, balls-sticks or licorice, as convert glyphs "
                                   "(default: balls-sticks below 20,000 atoms, spacefill from there on)")
      ->check(CLI::IsMember({"spacefill", "balls-sticks", "licorice"}))
      ->default_str("");
}

bool is_atom_colouring(std::string_view colour_by) {
  return colour_by == "element" || colour_by == "chain" || colour_by == "residue";
}

nlohmann::json molecule_json(const Model& glyphs) {
  nlohmann::json j = nlohmann::json::object();
  for (const char* key : {"style", "colour_by"})
    if (const auto it = glyphs.metadata.find(key); it != glyphs.metadata.end()) j[key] = it->second;
  for (const char* key : {"atoms", "bonds"})
    if (const auto it = glyphs.metadata.find(key); it != glyphs.metadata.end()) j[key] = std::stoull(it->second);
  return j;
}

bool is_point_cloud_file(const std::string& file) { return known_file_kind(file) == FileKind::points; }

Scene read_scene(const SceneFiles& files) {
  const bool is_molecule = !files.model.empty() && is_molecule_file(files.model);
  // The molecule options are refused before anything is read: they would change nothing.
  for (const auto& [option, value] : {std::pair{"--style", &files.style}, std::pair{"--colour-by", &files.colour_by}})
    if (!value->empty() && !is_molecule)
      throw CLI::ValidationError(
          option, fmt::format("'{}' is for a molecule MODEL (.pdb, .ent, .cif, .mmcif, optionally .gz); {}", *value,
                              files.model.empty() ? "none was given" : "'" + files.model + "' is not one"));
  Scene scene;
  if (is_molecule) {
    // The values were checked by the options (CLI::IsMember); the parsers name them otherwise.
    scene.model = read_molecule_glyphs(files.model,
                                       files.style.empty() ? std::nullopt : std::optional(parse_molecule_style(files.style)),
                                       files.colour_by.empty() ? ColourBy::element : parse_colour_by(files.colour_by));
    scene.kind = SceneInputKind::molecule;
  } else if (!files.model.empty()) {
    if (detect_file_kind(files.model) == FileKind::mesh) {
      if (!files.mesh.empty()) throw InvalidInput("give either a mesh as MODEL or --mesh, not both");
      scene.mesh = read_mesh(files.model);
      scene.kind = SceneInputKind::mesh;
    } else if (is_point_cloud_file(files.model)) {
      throw InvalidInput(fmt::format("{}: a point cloud (no faces), not a model or a mesh; render draws one over a "
                                     "model with --points",
                                     files.model));
    } else {
      scene.model = read_model(files.model);  // .qxm, .slim2t; it names what is wrong with anything else
      scene.kind = SceneInputKind::model;
    }
  }
  if (!files.mesh.empty()) scene.mesh = read_mesh(files.mesh);
  return scene;
}

}  // namespace quadrix::cli
