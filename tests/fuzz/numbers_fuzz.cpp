// Fuzz target: the number parsing every text reader shares (io/common/number_format.hpp). What it
// accepts it reads correctly rounded (as glibc's strtod, the C standard's reference), and the
// shortest text written for a double reads back as the same double, bit for bit.
#include "io/common/number_format.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

using namespace toposimp;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    double value = 0;
    if (io::parse_number(text, value)) {
        // The same text through strtod (which also takes what from_chars refuses: only compared
        // when strtod reads the whole text, and not for hexadecimal or infinity spellings).
        const std::string plain = !text.empty() && text[0] == '+' ? text.substr(1) : text;
        char* end = nullptr;
        const double reference = std::strtod(plain.c_str(), &end);
        if (end == plain.c_str() + plain.size() && plain.find_first_of("xXiInN") == std::string::npos &&
            std::memcmp(&reference, &value, sizeof value) != 0) {
            std::abort();
        }
        if (!std::isnan(value)) {
            std::string written;
            io::append_number(written, value);
            double back = 0;
            if (!io::parse_number(written, back) || std::memcmp(&back, &value, sizeof value) != 0) std::abort();
        }
    }
    // Any 8 bytes as a double round-trip through the writer.
    if (size >= 8) {
        double bits = 0;
        std::memcpy(&bits, data, 8);
        if (!std::isnan(bits)) {
            std::string written;
            io::append_number(written, bits);
            double back = 0;
            if (!io::parse_number(written, back) || std::memcmp(&back, &bits, sizeof bits) != 0) std::abort();
        }
    }
    return 0;
}
