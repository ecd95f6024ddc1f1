#pragma once
/// GLSL sources from render/shaders/*.glsl, embedded into the binary at build time.
#include <string_view>

namespace quadrix::render {

/// The text of render/shaders/NAME. \throws GlError for an unknown name.
std::string_view shader_source(std::string_view name);

}  // namespace quadrix::render
