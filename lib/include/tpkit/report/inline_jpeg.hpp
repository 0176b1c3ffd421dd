// A picture inline in a self-contained HTML page: 8-bit pixels encoded as JPEG in memory (libjpeg) and
// written as a data URI ("data:image/jpeg;base64,...", RFC 2397 and RFC 4648 base64).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace tpkit {

// `pixels`: rows top to bottom, `channels` 1 (grey) or 3 (red, green, blue) interleaved, width * height *
// channels bytes; quality 1..100. std::invalid_argument for a size that does not agree.
std::string jpeg_data_uri(const std::vector<uint8_t>& pixels, int width, int height, int channels, int quality);

// RFC 4648 base64 with padding.
std::string base64_encode(const uint8_t* data, size_t size);

}  // namespace tpkit
