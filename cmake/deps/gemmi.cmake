# gemmi (Debian: gemmi-dev 0.5.7), header-only structural-biology library: PDB and mmCIF
# reading. Its CIF parser needs PEGTL (Debian: tao-pegtl-dev). Used only by
# convert/read_molecule.cpp.
find_path(GEMMI_INCLUDE_DIR gemmi/mmread.hpp REQUIRED)
find_path(PEGTL_INCLUDE_DIR tao/pegtl.hpp REQUIRED)
find_package(ZLIB REQUIRED)
add_library(quadrix_gemmi INTERFACE)
target_include_directories(quadrix_gemmi SYSTEM INTERFACE ${GEMMI_INCLUDE_DIR} ${PEGTL_INCLUDE_DIR})
target_link_libraries(quadrix_gemmi INTERFACE ZLIB::ZLIB)
