# Writes ${OUT}: a C++ file holding every shader file (.glsl .vert .frag) of ${SHADER_DIR} as a string literal.
file(GLOB shader_files RELATIVE ${SHADER_DIR} ${SHADER_DIR}/*.glsl ${SHADER_DIR}/*.vert ${SHADER_DIR}/*.frag)
list(SORT shader_files)
set(body "")
foreach(f ${shader_files})
  file(READ ${SHADER_DIR}/${f} text)
  string(APPEND body "    {\"${f}\", R\"quadrix_glsl(${text})quadrix_glsl\"},\n")
endforeach()
file(WRITE ${OUT}.new
"// Generated from render/shaders/*.glsl by render/embed_shaders.cmake. Do not edit.
#include \"render/shaders.h\"

#include <fmt/format.h>

#include <map>

#include \"core/error.h\"

namespace quadrix::render {

std::string_view shader_source(std::string_view name) {
  static const std::map<std::string_view, std::string_view> sources{
${body}  };
  const auto it = sources.find(name);
  if (it == sources.end()) throw GlError(fmt::format(\"no embedded shader '{}'\", name));
  return it->second;
}

}  // namespace quadrix::render
")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${OUT}.new ${OUT})
