# nanoflann (Debian: libnanoflann-dev), header-only kd-tree: used by fit/point_index.cpp and core/slim_lod.cpp.
find_package(nanoflann REQUIRED)
