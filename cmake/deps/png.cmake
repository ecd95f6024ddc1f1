find_package(PNG REQUIRED)
find_package(JPEG REQUIRED)
