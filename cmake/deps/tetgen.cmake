# TetGen 1.5 (libtet1.5-dev) is AGPL: it is linked only into its own target (quadrix_tetgen).
find_path(TETGEN_INCLUDE_DIR tetgen.h REQUIRED)
find_library(TETGEN_LIBRARY tet REQUIRED)
add_library(TetGen::tet UNKNOWN IMPORTED)
set_target_properties(TetGen::tet PROPERTIES IMPORTED_LOCATION ${TETGEN_LIBRARY}
                                             INTERFACE_INCLUDE_DIRECTORIES ${TETGEN_INCLUDE_DIR}
                                             INTERFACE_COMPILE_DEFINITIONS TETLIBRARY)
