// The fuzz build's stb_image and stb_image_write: the code of Debian's libstb headers
// (the same version libstb.so is built from), compiled here with the fuzzer's
// instrumentation so that libFuzzer sees coverage inside the decoders and ASan/UBSan
// check them. Every other build links Debian's libstb (src/CMakeLists.txt, mr_stb).
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
