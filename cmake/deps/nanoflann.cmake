# nanoflann (Debian: libnanoflann-dev), header-only kd-tree: used only by fit/point_index.cpp.
find_package(nanoflann REQUIRED)
