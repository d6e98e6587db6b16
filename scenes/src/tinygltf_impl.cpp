// Compiles tinygltf's implementation once for the importer and the exporter (both include
// tinygltf_config.h so they agree on the configuration macros).
#define TINYGLTF_IMPLEMENTATION
#include "tinygltf_config.h"
