#include "vismask/scene/jpeg.h"

#include <jpeglib.h>

#include <csetjmp>
#include <cstdio>  // jpeglib.h needs FILE and size_t declared first

namespace vismask {

namespace {

// libjpeg reports an error by calling error_exit, which must not return:
// it jumps back to the setjmp in Run. Warnings (emit_message with level -1:
// corrupt data that the decoder would paper over) jump too.
struct ErrorManager {
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void OnError(j_common_ptr c) {
  ErrorManager* e = reinterpret_cast<ErrorManager*>(c->err);
  (*c->err->format_message)(c, e->message);
  std::longjmp(e->jump, 1);
}

void OnMessage(j_common_ptr c, int level) {
  if (level < 0) OnError(c);  // a warning: corrupt data
}

// libjpeg's messages quote no byte of the file, but the rule for every
// decoder message is printable ASCII only.
std::string Printable(const char* s) {
  std::string out;
  for (; *s; ++s) {
    const unsigned char u = static_cast<unsigned char>(*s);
    if (u >= 0x20 && u < 0x7f) {
      out += *s;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", u);
      out += hex;
    }
  }
  return out;
}

// One decompression from header to the last row, or to the header only
// (rows == nullptr). Between setjmp and a longjmp only trivially
// destructible objects live in this frame.
bool Run(const unsigned char* b, size_t n, int* width, int* height, uint8_t* rows, size_t rowsSize,
         ErrorManager* err) {
  jpeg_decompress_struct d;
  d.err = jpeg_std_error(&err->pub);
  err->pub.error_exit = OnError;
  err->pub.emit_message = OnMessage;
  err->message[0] = '\0';
  if (setjmp(err->jump)) {
    jpeg_destroy_decompress(&d);
    return false;
  }
  jpeg_create_decompress(&d);
  jpeg_mem_src(&d, b, static_cast<unsigned long>(n));
  jpeg_read_header(&d, TRUE);
  *width = static_cast<int>(d.image_width);
  *height = static_cast<int>(d.image_height);
  if (!rows) {
    jpeg_destroy_decompress(&d);
    return true;
  }
  d.out_color_space = JCS_RGB;
  d.dct_method = JDCT_ISLOW;  // the exact integer transform: the same texels everywhere
  jpeg_start_decompress(&d);
  const size_t stride = size_t{d.output_width} * 3;
  if (d.output_components != 3 || size_t{d.output_height} * stride != rowsSize) {
    std::snprintf(err->message, sizeof err->message, "decoder output is not %dx%d RGB", *width,
                  *height);
    jpeg_destroy_decompress(&d);
    return false;
  }
  while (d.output_scanline < d.output_height) {
    JSAMPROW row = rows + size_t{d.output_scanline} * stride;
    jpeg_read_scanlines(&d, &row, 1);
  }
  jpeg_finish_decompress(&d);
  jpeg_destroy_decompress(&d);
  return true;
}

}  // namespace

bool IsJpeg(const unsigned char* b, size_t n) {
  return n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
}

std::string JpegSize(const unsigned char* b, size_t n, int* width, int* height) {
  ErrorManager err;
  if (!Run(b, n, width, height, nullptr, 0, &err)) return Printable(err.message);
  return "";
}

std::string DecodeJpeg(const unsigned char* b, size_t n, int* width, int* height,
                       std::vector<uint8_t>* rgb) {
  ErrorManager err;
  if (!Run(b, n, width, height, nullptr, 0, &err)) return Printable(err.message);
  if (*width <= 0 || *height <= 0) return "no texels";
  rgb->assign(size_t(*width) * size_t(*height) * 3, 0);
  if (!Run(b, n, width, height, rgb->data(), rgb->size(), &err)) {
    rgb->clear();
    return Printable(err.message);
  }
  return "";
}

}  // namespace vismask
