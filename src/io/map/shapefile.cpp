#include "io/map/shapefile.hpp"

#include "io/common/errors.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <span>

namespace toposimp::io {
namespace {

// A file read front to back through a buffer; every read fails past the end.
class SequentialFile {
public:
    // The buffer: a megabyte, or the whole file if it is smaller (no megabyte zeroed for a
    // .shx of a few records, three files a read).
    explicit SequentialFile(const std::filesystem::path& path) : in_(path, std::ios::binary) {
        std::error_code error;
        const std::uintmax_t size = std::filesystem::file_size(path, error);
        buffer_.resize(error ? kBuffer : static_cast<std::size_t>(std::clamp<std::uintmax_t>(size, 1, kBuffer)));
    }

    bool is_open() const { return in_.is_open(); }
    std::uint64_t offset() const { return offset_; }

    bool take(unsigned char* out, std::size_t count) {
        while (count > 0) {
            if (at_ == filled_ && !refill()) return false;
            const std::size_t n = std::min(count, filled_ - at_);
            std::memcpy(out, buffer_.data() + at_, n);
            at_ += n;
            offset_ += n;
            out += n;
            count -= n;
        }
        return true;
    }

    // The next `count` bytes: in the buffer where they all lie in it, else copied to `scratch`;
    // nullptr past the end.
    const unsigned char* view(std::size_t count, std::vector<unsigned char>& scratch) {
        if (filled_ - at_ >= count) {
            const unsigned char* bytes = buffer_.data() + at_;
            at_ += count;
            offset_ += count;
            return bytes;
        }
        scratch.resize(count);
        return take(scratch.data(), count) ? scratch.data() : nullptr;
    }

    bool skip(std::uint64_t count) {
        while (count > 0) {
            if (at_ == filled_ && !refill()) return false;
            const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(count, filled_ - at_));
            at_ += n;
            offset_ += n;
            count -= n;
        }
        return true;
    }

private:
    bool refill() {
        in_.read(reinterpret_cast<char*>(buffer_.data()), static_cast<std::streamsize>(buffer_.size()));
        filled_ = static_cast<std::size_t>(in_.gcount());
        at_ = 0;
        return filled_ > 0;
    }

    static constexpr std::size_t kBuffer = std::size_t{1} << 20;
    std::ifstream in_;
    std::vector<unsigned char> buffer_;
    std::size_t filled_ = 0;
    std::size_t at_ = 0;
    std::uint64_t offset_ = 0;
};

std::uint32_t big_u32(const unsigned char* bytes) {
    return std::uint32_t{bytes[0]} << 24 | std::uint32_t{bytes[1]} << 16 | std::uint32_t{bytes[2]} << 8 | bytes[3];
}

std::uint32_t little_u32(const unsigned char* bytes) {
    return std::uint32_t{bytes[3]} << 24 | std::uint32_t{bytes[2]} << 16 | std::uint32_t{bytes[1]} << 8 | bytes[0];
}

double little_f64(const unsigned char* bytes) {
    // One load where the machine is little-endian (the byte-by-byte assembly took 0.06 s of
    // GSHHG's read; issue 34).
    std::uint64_t bits = 0;
    if constexpr (std::endian::native == std::endian::little) {
        std::memcpy(&bits, bytes, sizeof bits);
    } else {
        for (int i = 0; i < 8; ++i) bits |= std::uint64_t{bytes[i]} << (8 * i);
    }
    double value = 0;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}

// The sibling of `shp` with this extension, in the case the .shp's extension is written in.
std::filesystem::path sibling(const std::filesystem::path& shp, const char* lower, const char* upper) {
    const std::string extension = shp.extension().string();
    const bool is_upper = extension.size() == 4 && extension[1] == 'S';
    std::filesystem::path path = shp;
    path.replace_extension(is_upper ? upper : lower);
    return path;
}

// The 100-byte header of a .shp or .shx: file code 9994 and version 1000; returns the shape type.
std::optional<std::uint32_t> shape_header(SequentialFile& file) {
    std::array<unsigned char, 100> header{};
    if (!file.take(header.data(), header.size())) return std::nullopt;
    if (big_u32(&header[0]) != 9994 || little_u32(&header[28]) != 1000) return std::nullopt;
    return little_u32(&header[32]);
}

bool is_point_type(std::uint32_t type) { return type == 1 || type == 11 || type == 21; }
bool is_multipoint_type(std::uint32_t type) { return type == 8 || type == 18 || type == 28; }
bool is_poly_type(std::uint32_t type) { return type == 3 || type == 5 || type == 13 || type == 15 || type == 23 || type == 25; }

// Calls visit(fid, deleted, content) for every record of the .shp at `path` whose file shape
// type passes `accepts`, `content` being the record after its 8-byte header (at least the
// 4-byte shape type, which is 0 or the file's unless the record is deleted), valid during the
// call. False when a sibling file is missing, the files disagree, or visit returns false.
template <class Accepts, class Visit>
bool for_each_record(const std::string& path, Accepts accepts, Visit visit) {
    const std::filesystem::path shp_path(path);
    SequentialFile shp(shp_path);
    const std::filesystem::path shx_path = sibling(shp_path, ".shx", ".SHX");
    SequentialFile shx(shx_path);
    SequentialFile dbf(sibling(shp_path, ".dbf", ".DBF"));
    if (!shp.is_open() || !shx.is_open() || !dbf.is_open()) return false;

    const std::optional<std::uint32_t> file_type = shape_header(shp);
    if (!file_type || shape_header(shx) != file_type) return false;
    if (*file_type != 0 && !accepts(*file_type)) return false;
    std::error_code error;
    const std::uintmax_t shx_size = std::filesystem::file_size(shx_path, error);
    if (error || shx_size < 100 || (shx_size - 100) % 8 != 0) return false;
    const std::uint64_t records = (shx_size - 100) / 8;
    const std::uintmax_t shp_size = std::filesystem::file_size(shp_path, error);
    if (error) return false;

    // dBASE header: record count, header length and record length; each record starts with
    // its deletion flag ('*' deleted, ' ' not).
    std::array<unsigned char, 12> dbf_header{};
    if (!dbf.take(dbf_header.data(), dbf_header.size())) return false;
    const std::uint32_t dbf_records = little_u32(&dbf_header[4]);
    const unsigned dbf_header_length = dbf_header[8] | unsigned{dbf_header[9]} << 8;
    const unsigned dbf_record_length = dbf_header[10] | unsigned{dbf_header[11]} << 8;
    if (dbf_records != records || dbf_record_length == 0 || dbf_header_length < 12 || !dbf.skip(dbf_header_length - 12)) {
        return false;
    }

    std::vector<unsigned char> scratch;  // a record the read buffer does not hold whole
    for (std::uint64_t fid = 0; fid < records; ++fid) {
        unsigned char index[8], record_header[8], deletion = 0;
        if (!shx.take(index, 8) || !dbf.take(&deletion, 1) || !dbf.skip(dbf_record_length - 1)) return false;
        // The .shx locates every record (as OGR reads them); here they must follow one another.
        const std::uint64_t offset = std::uint64_t{big_u32(index)} * 2, length = std::uint64_t{big_u32(index + 4)} * 2;
        if (offset != shp.offset() || !shp.take(record_header, 8) || std::uint64_t{big_u32(record_header + 4)} * 2 != length) {
            return false;
        }
        // A length is held against the file before anything is allocated for it (issue 29: a
        // 10 KB file claiming a 2 GB record).
        if (length < 4 || length > shp_size - std::min<std::uint64_t>(shp_size, shp.offset())) return false;
        const unsigned char* bytes = shp.view(static_cast<std::size_t>(length), scratch);
        if (bytes == nullptr) return false;
        if (deletion != '*' && deletion != ' ') return false;
        const std::uint32_t type = little_u32(bytes);
        if (deletion == ' ' && type != 0 && type != *file_type) return false;
        if (!visit(fid, deletion == '*', std::span<const unsigned char>(bytes, static_cast<std::size_t>(length)))) return false;
    }
    return true;
}

}  // namespace

std::optional<std::vector<Point>> read_shapefile_points(const std::string& path) {
    std::vector<Point> points;
    const bool read = for_each_record(
        path, [](std::uint32_t type) { return is_point_type(type) || is_multipoint_type(type); },
        [&](std::uint64_t fid, bool deleted, std::span<const unsigned char> content) {
            const std::uint32_t type = little_u32(content.data());
            if (deleted || type == 0) return true;
            const std::size_t length = content.size(), before = points.size();
            if (is_point_type(type)) {
                if (length < 20) return false;
                points.push_back({little_f64(&content[4]), little_f64(&content[12])});
            } else {
                if (length < 40) return false;
                const std::uint64_t count = little_u32(&content[36]);
                if (length < 40 + 16 * count) return false;
                for (std::uint64_t i = 0; i < count; ++i) {
                    points.push_back({little_f64(&content[40 + 16 * i]), little_f64(&content[48 + 16 * i])});
                }
            }
            for (std::size_t i = before; i < points.size(); ++i) {
                if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
                    throw InputError("'" + path + "', layer '" + std::filesystem::path(path).stem().string() + "', feature " +
                                     std::to_string(fid) + ": control point has a non-finite coordinate");
                }
            }
            return true;
        });
    if (!read) return std::nullopt;
    return points;
}

ShapeRecord ShapeTable::operator[](std::size_t r) const {
    const std::size_t first = record_first[r], end = record_first[r + 1];
    return {{xy.data() + first, end - first},
            z.empty() ? std::span<const double>() : std::span<const double>(z.data() + first, end - first),
            {part_starts.data() + record_parts[r], record_parts[r + 1] - record_parts[r]}};
}

namespace {

// Appends a PolyLine or Polygon record's content (after its shape type, which is `type`) to the
// arrays: its part starts, vertices and, for Z types, z values. False if the record is not
// whole. `has_z` is set by the first record that is not null (the file's type is every one's).
bool append_shape(std::span<const unsigned char> content, std::uint32_t type, std::optional<bool>& has_z, std::vector<Point>& xy,
                  std::vector<double>& z, std::vector<std::uint32_t>& part_starts) {
    // Box (32 bytes), part and point counts, the parts' first points, the points; for Z types
    // then the z range and the z values (M values after them are not read).
    const std::uint64_t length = content.size();
    if (length < 44) return false;
    const std::uint64_t parts = little_u32(&content[36]), count = little_u32(&content[40]);
    const std::uint64_t points_at = 44 + 4 * parts, z_at = points_at + 16 * count + 16;
    if (!has_z) has_z = type == 13 || type == 15;
    if (length < points_at + 16 * count || (*has_z && length < z_at + 8 * count)) return false;
    if (parts == 0 && count != 0) return false;
    for (std::uint64_t k = 0; k < parts; ++k) {
        const std::uint32_t start = little_u32(&content[44 + 4 * k]);
        if (start >= count || (k == 0 ? start != 0 : start <= part_starts.back())) return false;
        part_starts.push_back(start);
    }
    for (std::size_t i = 0; i < count; ++i) {
        xy.push_back({little_f64(&content[points_at + 16 * i]), little_f64(&content[points_at + 16 * i + 8])});
    }
    if (*has_z) {
        z.resize(xy.size() - count);  // (records before all null)
        for (std::size_t i = 0; i < count; ++i) z.push_back(little_f64(&content[z_at + 8 * i]));
    }
    return true;
}

}  // namespace

std::optional<ShapeTable> read_shapefile_shapes(const std::string& path) {
    ShapeTable table;
    // Room for as many records, parts and vertices as the files can hold (8 bytes of .shx a
    // record; 16 bytes of .shp a vertex, and 20 a part: its start and at least one vertex),
    // address space only until written: the arrays never grow, so never copy.
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    const std::uintmax_t shx_size = std::filesystem::file_size(sibling(path, ".shx", ".SHX"), error);
    if (error) return std::nullopt;
    table.xy.reserve(static_cast<std::size_t>(size / 16));
    table.part_starts.reserve(static_cast<std::size_t>(size / 20));
    table.record_first.reserve(static_cast<std::size_t>(shx_size / 8 + 1));
    table.record_parts.reserve(static_cast<std::size_t>(shx_size / 8 + 1));
    table.record_first.push_back(0);
    table.record_parts.push_back(0);
    std::optional<bool> has_z;
    const bool read = for_each_record(path, is_poly_type, [&](std::uint64_t, bool deleted, std::span<const unsigned char> content) {
        if (deleted) return false;  // (not in a file just written)
        const std::uint32_t type = little_u32(content.data());
        if (type != 0 && table.z.empty() && (type == 13 || type == 15)) table.z.reserve(static_cast<std::size_t>(size / 24));
        if (type != 0 && !append_shape(content, type, has_z, table.xy, table.z, table.part_starts)) return false;
        table.record_first.push_back(table.xy.size());
        table.record_parts.push_back(table.part_starts.size());
        return true;
    });
    if (!read) return std::nullopt;
    return table;
}

bool for_each_shape(const std::string& path, const std::function<bool(std::uint64_t, const ShapeRecord&)>& visit) {
    std::vector<Point> xy;
    std::vector<double> z;
    std::vector<std::uint32_t> part_starts;
    std::optional<bool> has_z;
    return for_each_record(path, is_poly_type, [&](std::uint64_t fid, bool deleted, std::span<const unsigned char> content) {
        if (deleted) return false;
        const std::uint32_t type = little_u32(content.data());
        xy.clear();
        z.clear();
        part_starts.clear();
        if (type != 0 && !append_shape(content, type, has_z, xy, z, part_starts)) return false;
        return visit(fid, ShapeRecord{xy, z, part_starts});
    });
}

}  // namespace toposimp::io
