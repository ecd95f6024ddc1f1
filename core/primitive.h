#pragma once
/// Kinds of drawn primitive and the per-pixel id that names one in a G-buffer or a reference
/// image: kind·2²⁸ + index, −1 for the background.
#include <cstddef>
#include <cstdint>

namespace quadrix {

/// Every kind a renderer draws (the value is the id's top bits).
enum class PrimitiveKind : std::uint8_t { none = 0, slim = 1, tet = 2, glyph = 3, mesh = 4, implicit = 5 };

/// Bits of an id that hold the index; larger indices cannot be named.
inline constexpr int kPrimitiveIndexBits = 28;
inline constexpr std::size_t kMaxPrimitiveIndex = (std::size_t(1) << kPrimitiveIndexBits) - 1;

/// The id of primitive `index` of `kind` (index ≤ kMaxPrimitiveIndex; a mesh's index is its triangle).
constexpr std::int32_t primitive_id(PrimitiveKind kind, std::size_t index) {
  return static_cast<std::int32_t>((static_cast<std::uint32_t>(kind) << kPrimitiveIndexBits) |
                                   static_cast<std::uint32_t>(index));
}

/// The kind an id names (none for −1).
constexpr PrimitiveKind primitive_kind(std::int32_t id) {
  return id < 0 ? PrimitiveKind::none : static_cast<PrimitiveKind>(id >> kPrimitiveIndexBits);
}

}  // namespace quadrix
