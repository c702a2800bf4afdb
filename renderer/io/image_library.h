#pragma once
// OpenImageIO behind dlopen. Linked into omega and omegad it loaded about 250 shared libraries
// before main at every start (0.25 s on a 2-core machine, for `omega status` as for a render),
// although only textures, environment maps, the references of `omega compare` and `converge`,
// and the breakdown chart need it. Those calls go through this table, which the module
// libomega_images.so (image_library_oiio.cpp, the only code that includes OpenImageIO) fills;
// image_library() opens it on first use.
#include <string>

#include "texture/image.h"

namespace omega {

// Raised whenever the table changes shape: a module from another build is refused, not called.
inline constexpr int kImageLibraryAbi = 1;

// Each function returns "" on success, else why it failed (OpenImageIO's message).
struct ImageLibrary {
    int abi = 0;
    // Decodes an image held in memory, whose OpenImageIO format name is `format`. No reader
    // sees a path it could open: it gets `path`'s file name under /proc, and messages show
    // `name` instead. Refuses more than 2^26 texels or 64 channels before decoding any pixel.
    std::string (*decode)(const std::string& bytes, const std::string& format, const std::string& path,
                          const std::string& name, ImagePixels& out);
    // Reads an image file (any format OpenImageIO reads): subimage 0, every channel, as float.
    std::string (*read_file)(const std::string& path, ImagePixels& out);
    // Filtered resize of a float image to width x height (OpenImageIO's filter names:
    // "triangle", "gaussian").
    std::string (*resize)(const ImagePixels& in, int width, int height, const std::string& filter, ImagePixels& out);
    // Error of img against ref (same size and channels): out = {RMSE, relMSE, MAPE, mean ratio},
    // relMSE = mean (x - r)^2 / (r^2 + eps), MAPE = mean |x - r| / (|r| + eps), means over
    // pixels and channels.
    std::string (*compare)(const ImagePixels& img, const ImagePixels& ref, double eps, double out[4]);
    // Writes 8-bit RGB rows (top first), the format chosen by the path's extension.
    std::string (*write_rgb8)(const std::string& path, int width, int height, const unsigned char* rgb);
};

// Any thread; opens the module once. It looks in $OMEGA_IMAGE_LIBRARY if set (and only there),
// else beside the executable, in ../lib/omega beside it, and where this build put it. Throws
// std::runtime_error naming every place it tried.
const ImageLibrary& image_library();

}  // namespace omega

// The module's one export.
extern "C" const omega::ImageLibrary* omega_image_library();
