// Ball sets with element radii and CPK colours: molecules (read_molecule), .cin and .xyzr.
#include "convert/balls.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "convert/molecule.h"
#include "core/error.h"
#include "core/io/file.h"
#include "core/io/text_reader.h"
#include "core/limits.h"
#include "core/log.h"

namespace quadrix {
namespace {

namespace fs = std::filesystem;

struct Element {
  const char* symbol;
  double vdw, covalent;
  Rgb cpk;
};

// Bondi (1964) van der Waals radii (H: Rowland & Taylor 1996), Cordero et al. (2008) covalent
// radii, Jmol CPK colours.
constexpr Element kElements[] = {
    {"H", 1.10, 0.31, {255, 255, 255}},  {"C", 1.70, 0.76, {144, 144, 144}}, {"N", 1.55, 0.71, {48, 80, 248}},
    {"O", 1.52, 0.66, {255, 13, 13}},    {"S", 1.80, 1.05, {255, 255, 48}},  {"P", 1.80, 1.07, {255, 128, 0}},
    {"F", 1.47, 0.57, {144, 224, 80}},   {"CL", 1.75, 1.02, {31, 240, 31}},  {"BR", 1.85, 1.20, {166, 41, 41}},
    {"I", 1.98, 1.39, {148, 0, 148}},    {"SE", 1.90, 1.20, {255, 161, 0}},  {"NA", 2.27, 1.66, {171, 92, 242}},
    {"K", 2.75, 2.03, {143, 64, 212}},   {"MG", 1.73, 1.41, {138, 255, 0}},  {"CA", 2.31, 1.76, {61, 255, 0}},
    {"FE", 2.00, 1.32, {224, 102, 51}},  {"ZN", 1.39, 1.22, {125, 128, 176}}, {"CU", 1.40, 1.32, {200, 128, 51}},
    {"MN", 2.00, 1.39, {156, 122, 199}}, {"CO", 2.00, 1.26, {240, 144, 160}}, {"NI", 1.63, 1.24, {80, 208, 80}},
};
constexpr double kDefaultVdw = 1.8, kDefaultCovalent = 1.5;
constexpr Rgb kUnknownColour{255, 20, 147};

const Element* find_element(std::string_view e) {
  for (const auto& x : kElements)
    if (e == x.symbol) return &x;
  return nullptr;
}

std::vector<Ball> read_pdb(const fs::path& path, const BallReadOptions& o, std::vector<int>& serials) {
  const Molecule mol = read_molecule(path, {.water = o.water});
  std::vector<Ball> balls;
  balls.reserve(mol.atoms.size());
  std::map<std::string, int> unknown;
  for (const Atom& a : mol.atoms) {
    Ball b;
    b.centre = a.position;
    b.element = a.element;
    if (!find_element(b.element)) ++unknown[b.element];
    b.radius = element_radius(b.element, o.radii) * o.radius_scale;
    b.colour = cpk_colour(b.element);
    balls.push_back(std::move(b));
    serials.push_back(a.serial);
  }
  for (const auto& [e, n] : unknown)
    log::warn("{}: {} atoms of unknown element '{}' get the default radius", path.string(), n, e);
  if (mol.waters_left_out > 0) log::info("{}: {} water atoms left out", path.string(), mol.waters_left_out);
  return balls;
}

std::vector<Ball> read_columns(const fs::path& path, const BallReadOptions& o, bool weights, std::vector<int>& lines) {
  const std::string text = io::read_file(path);
  io::TextReader in(text, path);
  const char* size = weights ? "weight (squared radius)" : "radius";
  std::vector<Ball> balls;
  while (in.next_line()) {
    std::array<double, 4> v{};
    for (auto& x : v) {
      const std::string_view w = in.token();
      if (w.empty()) in.fail("expected 4 numbers (x y z {}), got '{}'", weights ? "w" : "r", io::echo(in.line()));
      if (!io::TextReader::parse(w, x) || !std::isfinite(x)) in.fail("'{}' is not a finite number", io::echo(w));
    }
    if (const std::string_view extra = in.token(); !extra.empty()) in.fail("more than 4 values ('{}')", io::echo(extra));
    if (!(v[3] > 0)) in.fail("{} {} must be > 0", size, v[3]);
    Ball b;
    b.centre = {v[0], v[1], v[2]};
    b.radius = (weights ? std::sqrt(v[3]) : v[3]) * o.radius_scale;
    if (!is_world_point(b.centre)) in.fail("ball centre ({:g}, {:g}, {:g}) {}", v[0], v[1], v[2], world_fault(b.centre));
    if (!is_world_value(b.radius)) {  // where the radius came from, when it is not the value read
      const std::string scale = o.radius_scale == 1 ? "" : fmt::format(" times the radius scale {:g}", o.radius_scale);
      const std::string from = b.radius == v[3] ? "" : fmt::format(" (from {} {:g}{})", size, v[3], scale);
      in.fail("ball radius {:g}{} {}", b.radius, from, world_fault(b.radius));
    }
    balls.push_back(b);
    lines.push_back(static_cast<int>(in.line_number()));
  }
  return balls;
}

// Indices of the first pair of centres closer than tol, if any.
std::optional<std::pair<std::size_t, std::size_t>> find_duplicate(const std::vector<Ball>& balls, double tol) {
  std::vector<std::size_t> order(balls.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return balls[a].centre.x() < balls[b].centre.x(); });
  for (std::size_t i = 0; i < order.size(); ++i)
    for (std::size_t j = i + 1; j < order.size() && balls[order[j]].centre.x() - balls[order[i]].centre.x() <= tol; ++j)
      if ((balls[order[i]].centre - balls[order[j]].centre).norm() <= tol)
        return std::pair{std::min(order[i], order[j]), std::max(order[i], order[j])};
  return std::nullopt;
}

double extent(const std::vector<Ball>& balls) {
  Box3 box;
  for (const auto& b : balls) box.extend(b.centre);
  return std::max(box.diagonal(), 1e-300);
}

}  // namespace

RadiusTable parse_radius_table(std::string_view name) {
  if (name == "vdw") return RadiusTable::vdw;
  if (name == "covalent") return RadiusTable::covalent;
  if (name == "unit") return RadiusTable::unit;
  throw InvalidInput(fmt::format("unknown radius table '{}' (vdw, covalent, unit)", name));
}

double element_radius(std::string_view element, RadiusTable table) {
  const Element* e = find_element(element);
  switch (table) {
    case RadiusTable::vdw: return e ? e->vdw : kDefaultVdw;
    case RadiusTable::covalent: return e ? e->covalent : kDefaultCovalent;
    case RadiusTable::unit: return 1.0;
  }
  return kDefaultVdw;
}

Rgb cpk_colour(std::string_view element) {
  const Element* e = find_element(element);
  return e ? e->cpk : kUnknownColour;
}

void validate_balls(const std::vector<Ball>& balls, std::string_view source) {
  if (balls.empty()) throw InvalidInput(fmt::format("{}: no balls", source));
  for (std::size_t i = 0; i < balls.size(); ++i) {
    if (!is_world_point(balls[i].centre) || !is_world_value(balls[i].radius))
      throw InvalidInput(fmt::format("{}: ball {} (centre ({:g}, {:g}, {:g}), radius {:g}) {}", source, i,
                                     balls[i].centre.x(), balls[i].centre.y(), balls[i].centre.z(), balls[i].radius,
                                     world_fault(is_world_point(balls[i].centre) ? Eigen::Vector3d::Constant(balls[i].radius)
                                                                                 : balls[i].centre)));
    if (!(balls[i].radius > 0)) throw InvalidInput(fmt::format("{}: ball {} has radius {} ≤ 0", source, i, balls[i].radius));
  }
  if (const auto d = find_duplicate(balls, 1e-6 * extent(balls)))
    throw InvalidInput(fmt::format("{}: balls {} and {} have the same centre ({}, {}, {})", source, d->first, d->second,
                                   balls[d->first].centre.x(), balls[d->first].centre.y(), balls[d->first].centre.z()));
}

std::vector<Ball> read_balls(const fs::path& path, const BallReadOptions& options) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (!(options.radius_scale > 0) || !std::isfinite(options.radius_scale))
    throw InvalidInput(fmt::format("radius scale {} must be finite and > 0", options.radius_scale));
  std::vector<int> lines;  // per ball: the line (.cin, .xyzr) or the atom serial number (molecules)
  std::vector<Ball> balls;
  const bool molecule = is_molecule_file(path);
  if (molecule) balls = read_pdb(path, options, lines);
  else if (ext == ".cin") balls = read_columns(path, options, true, lines);
  else if (ext == ".xyzr") balls = read_columns(path, options, false, lines);
  else throw InvalidInput(fmt::format("'{}': unknown ball file type (.pdb, .ent, .cif, .mmcif, .cin, .xyzr)", path.string()));
  if (balls.empty()) throw FormatError(fmt::format("{}: no atoms or balls found", path.string()));
  for (std::size_t i = 0; i < balls.size(); ++i)
    if (!is_world_point(balls[i].centre) || !is_world_value(balls[i].radius))
      throw FormatError(fmt::format("{}: {} {}: ball at ({:g}, {:g}, {:g}) of radius {:g} {}", path.string(),
                                    molecule ? "atom with serial number" : "line", lines[i], balls[i].centre.x(),
                                    balls[i].centre.y(), balls[i].centre.z(), balls[i].radius,
                                    world_fault(is_world_point(balls[i].centre) ? Eigen::Vector3d::Constant(balls[i].radius)
                                                                                : balls[i].centre)));
  if (const auto d = find_duplicate(balls, 1e-6 * extent(balls)))
    throw FormatError(fmt::format("{}: {} {} and {}: duplicate ball at ({}, {}, {})", path.string(),
                                  molecule ? "atoms with serial numbers" : "lines", lines[d->first],
                                  lines[d->second], balls[d->first].centre.x(), balls[d->first].centre.y(),
                                  balls[d->first].centre.z()));
  return balls;
}

}  // namespace quadrix
