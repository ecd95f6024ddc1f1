# OpenGL contexts: OSMesa (software, headless), EGL (surfaceless; the GPU path), GLFW (window).
find_package(PkgConfig REQUIRED)
pkg_check_modules(OSMESA REQUIRED IMPORTED_TARGET osmesa)
pkg_check_modules(EGL REQUIRED IMPORTED_TARGET egl)
find_package(glfw3 3.3 REQUIRED)
