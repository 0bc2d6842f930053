#pragma once
// JPEG textures through libjpeg-turbo (init only; it allocates with malloc).
//
// Why not stb_image's JPEG decoder, which reads the other formats: on
// corrupt entropy-coded data stb_image 2.27 (Debian 12's) reaches undefined
// behaviour that no check of the file's headers can rule out before
// decoding (a Huffman stream that drives its bit count negative, then a
// shift by 32). libjpeg-turbo is the reference decoder, fuzzed continuously
// upstream, and rejects such data with a message.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vismask {

// True when `b` starts with a JPEG's start-of-image marker and the next
// marker's first byte (FF D8 FF).
bool IsJpeg(const unsigned char* b, size_t n);

// The image's size from its header alone: "" and *width, *height, or the
// reason it cannot be read (printable ASCII only).
std::string JpegSize(const unsigned char* b, size_t n, int* width, int* height);

// Decodes the whole image to 8-bit sRGB triples (grey is expanded), top row
// first. Any warning of the decoder (corrupt or truncated data) is an error:
// the result is a whole, valid image or nothing (and a progressive file
// cannot repeat scans, which would decode for minutes, without a warning).
// Returns "" or the reason.
std::string DecodeJpeg(const unsigned char* b, size_t n, int* width, int* height,
                       std::vector<uint8_t>* rgb);

}  // namespace vismask
