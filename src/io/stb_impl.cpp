// stb_image and stb_image_write: the code of Debian's libstb headers (the version
// libstb.so is built from), compiled into every build (src/CMakeLists.txt, mr_stb):
// - PNG only (STBI_ONLY_PNG): stb_image's other decoders are not compiled in. JPEGs go
//   to libjpeg-turbo (src/render/image.cpp, decode_jpeg says why): Debian 12's stb JPEG
//   decoder trusts the file in ways fuzz/image_fuzz.cpp found three times;
// - with -fwrapv: the decoders do int arithmetic on values read from the file (the JPEG
//   DC overflow found by the fuzzer was one); wrapping is defined behaviour and gives
//   garbage pixels for a garbage file, not undefined behaviour;
// - with the build's instrumentation: the fuzzer sees coverage inside the decoder and
//   ASan/UBSan check it (the test suite's sanitizer build too).
#define STBI_ONLY_PNG
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
