# CGAL is header-only and heavy (30–65 s per translation unit): used only by convert/ and fit/.
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL REQUIRED)
