// tinygltf's implementation (Debian's header-only libtinygltf-dev), compiled
// once here with its file system and stb image parts off: the core touches
// no files, and the project file encodes its skin with io's PNG writer.
// <fstream>: tinygltf 2.7's file writers still name std::ofstream under
// TINYGLTF_NO_FS; nothing here calls them.
#include <fstream>
#define TINYGLTF_IMPLEMENTATION
#include <tiny_gltf.h>
