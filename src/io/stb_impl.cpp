// stb_image and stb_image_write: the code of Debian's libstb headers (the version
// libstb.so is built from), compiled into every build (src/CMakeLists.txt, mr_stb):
// - with -fwrapv: the decoders do int arithmetic on values read from the file, and a
//   crafted JPEG makes the DC coefficient times its quantiser overflow an int
//   (stb_image.h, stbi__jpeg_decode_block; found by fuzz/image_fuzz.cpp; newer upstream
//   stb refuses such files, Debian 12's does not). Wrapping is defined behaviour and
//   gives garbage pixels for a garbage file, not undefined behaviour;
// - with the build's instrumentation: the fuzzer sees coverage inside the decoders and
//   ASan/UBSan check them (the test suite's sanitizer build too).
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
