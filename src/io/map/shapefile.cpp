#include "io/map/shapefile.hpp"

#include "io/common/errors.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
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

    // The next byte read is at `offset` from the file's start.
    bool seek(std::uint64_t offset) {
        in_.clear();
        if (!in_.seekg(static_cast<std::streamoff>(offset))) return false;
        filled_ = at_ = 0;
        offset_ = offset;
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

// The records of a .shp (with its .shx and .dbf) one at a time, from a given record on: each
// record's FID, its deletion flag, and its content after the 8-byte header (at least the 4-byte
// shape type, which is 0 or the file's unless the record is deleted).
class RecordFiles {
public:
    enum class Next { record, end, failed };

    // False when a sibling file is missing, the files disagree or the file's shape type does not
    // pass `accepts`.
    template <class Accepts>
    bool open(const std::string& path, Accepts accepts) {
        const std::filesystem::path shp_path(path);
        const std::filesystem::path shx_path = sibling(shp_path, ".shx", ".SHX");
        shp_.emplace(shp_path);
        shx_.emplace(shx_path);
        dbf_.emplace(sibling(shp_path, ".dbf", ".DBF"));
        if (!shp_->is_open() || !shx_->is_open() || !dbf_->is_open()) return false;

        const std::optional<std::uint32_t> file_type = shape_header(*shp_);
        if (!file_type || shape_header(*shx_) != file_type) return false;
        if (*file_type != 0 && !accepts(*file_type)) return false;
        file_type_ = *file_type;
        std::error_code error;
        const std::uintmax_t shx_size = std::filesystem::file_size(shx_path, error);
        if (error || shx_size < 100 || (shx_size - 100) % 8 != 0) return false;
        records_ = (shx_size - 100) / 8;
        shp_size_ = std::filesystem::file_size(shp_path, error);
        if (error) return false;

        // dBASE header: record count, header length and record length; each record starts with
        // its deletion flag ('*' deleted, ' ' not).
        std::array<unsigned char, 12> dbf_header{};
        if (!dbf_->take(dbf_header.data(), dbf_header.size())) return false;
        const std::uint32_t dbf_records = little_u32(&dbf_header[4]);
        dbf_header_length_ = dbf_header[8] | unsigned{dbf_header[9]} << 8;
        dbf_record_length_ = dbf_header[10] | unsigned{dbf_header[11]} << 8;
        return dbf_records == records_ && dbf_record_length_ != 0 && dbf_header_length_ >= 12 && dbf_->skip(dbf_header_length_ - 12);
    }

    std::uint64_t records() const { return records_; }
    std::uintmax_t shp_size() const { return shp_size_; }

    // The next record read is `first` (at most records()): its .shx entry says where it is.
    bool seek(std::uint64_t first) {
        if (first > records_) return false;
        fid_ = first;
        if (first == records_) return true;
        unsigned char index[8];
        if (!shx_->seek(100 + 8 * first) || !shx_->take(index, 8) || !shx_->seek(100 + 8 * first)) return false;
        return shp_->seek(std::uint64_t{big_u32(index)} * 2) && dbf_->seek(dbf_header_length_ + first * dbf_record_length_);
    }

    Next next(std::uint64_t& fid, bool& deleted, std::span<const unsigned char>& content) {
        if (fid_ == records_) return Next::end;
        unsigned char index[8], record_header[8], deletion = 0;
        if (!shx_->take(index, 8) || !dbf_->take(&deletion, 1) || !dbf_->skip(dbf_record_length_ - 1)) return Next::failed;
        // The .shx locates every record (as OGR reads them); here they must follow one another.
        const std::uint64_t offset = std::uint64_t{big_u32(index)} * 2, length = std::uint64_t{big_u32(index + 4)} * 2;
        if (offset != shp_->offset() || !shp_->take(record_header, 8) || std::uint64_t{big_u32(record_header + 4)} * 2 != length) {
            return Next::failed;
        }
        // A length is held against the file before anything is allocated for it (issue 29: a
        // 10 KB file claiming a 2 GB record).
        if (length < 4 || length > shp_size_ - std::min<std::uint64_t>(shp_size_, shp_->offset())) return Next::failed;
        const unsigned char* bytes = shp_->view(static_cast<std::size_t>(length), scratch_);
        if (bytes == nullptr) return Next::failed;
        if (deletion != '*' && deletion != ' ') return Next::failed;
        const std::uint32_t type = little_u32(bytes);
        if (deletion == ' ' && type != 0 && type != file_type_) return Next::failed;
        fid = fid_++;
        deleted = deletion == '*';
        content = std::span<const unsigned char>(bytes, static_cast<std::size_t>(length));
        return Next::record;
    }

private:
    std::optional<SequentialFile> shp_, shx_, dbf_;
    std::uint32_t file_type_ = 0;
    std::uint64_t records_ = 0;
    std::uintmax_t shp_size_ = 0;
    unsigned dbf_header_length_ = 0, dbf_record_length_ = 0;
    std::uint64_t fid_ = 0;
    std::vector<unsigned char> scratch_;  // a record the read buffer does not hold whole
};

// Calls visit(fid, deleted, content) for every record of the .shp at `path` whose file shape
// type passes `accepts` (RecordFiles::next's record, valid during the call). False when a
// sibling file is missing, the files disagree, or visit returns false.
template <class Accepts, class Visit>
bool for_each_record(const std::string& path, Accepts accepts, Visit visit) {
    RecordFiles files;
    if (!files.open(path, accepts)) return false;
    for (;;) {
        std::uint64_t fid = 0;
        bool deleted = false;
        std::span<const unsigned char> content;
        switch (files.next(fid, deleted, content)) {
            case RecordFiles::Next::end: return true;
            case RecordFiles::Next::failed: return false;
            case RecordFiles::Next::record:
                if (!visit(fid, deleted, content)) return false;
                break;
        }
    }
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

struct ShapeReader::State {
    RecordFiles files;
    std::uint64_t end = 0;
    std::uint64_t next = 0;  // the next record's FID
    std::uint64_t fid = 0;   // the record last given
    bool failed = false;
    std::optional<bool> has_z;
    std::vector<Point> xy;
    std::vector<double> z;
    std::vector<std::uint32_t> part_starts;
    ShapeRecord record;
};

std::optional<ShapeReader> ShapeReader::open(const std::string& path, std::uint64_t first, std::uint64_t end) {
    auto state = std::make_unique<State>();
    if (!state->files.open(path, is_poly_type)) return std::nullopt;
    end = std::min(end, state->files.records());
    if (first > end || !state->files.seek(first)) return std::nullopt;
    state->end = end;
    state->next = first;
    return ShapeReader(std::move(state));
}

ShapeReader::ShapeReader(std::unique_ptr<State> state) : state_(std::move(state)) {}
ShapeReader::ShapeReader(ShapeReader&&) noexcept = default;
ShapeReader& ShapeReader::operator=(ShapeReader&&) noexcept = default;
ShapeReader::~ShapeReader() = default;

bool for_each_shape(const std::string& path, const std::function<bool(std::uint64_t, const ShapeRecord&)>& visit) {
    std::optional<ShapeReader> reader = ShapeReader::open(path);
    if (!reader) return false;
    while (const ShapeRecord* record = reader->next()) {
        if (!visit(reader->fid(), *record)) return false;
    }
    return !reader->failed();
}

std::uint64_t ShapeReader::records() const { return state_->files.records(); }
std::uintmax_t ShapeReader::shp_size() const { return state_->files.shp_size(); }
std::uint64_t ShapeReader::fid() const { return state_->fid; }
bool ShapeReader::failed() const { return state_->failed; }

const ShapeRecord* ShapeReader::next() {
    State& s = *state_;
    if (s.failed || s.next == s.end) return nullptr;
    std::uint64_t fid = 0;
    bool deleted = false;
    std::span<const unsigned char> content;
    if (s.files.next(fid, deleted, content) != RecordFiles::Next::record || deleted) {
        s.failed = true;
        return nullptr;
    }
    s.fid = fid;
    s.next = fid + 1;
    s.xy.clear();
    s.z.clear();
    s.part_starts.clear();
    const std::uint32_t type = little_u32(content.data());
    if (type != 0 && !append_shape(content, type, s.has_z, s.xy, s.z, s.part_starts)) {
        s.failed = true;
        return nullptr;
    }
    s.record = ShapeRecord{s.xy, s.z, s.part_starts};
    return &s.record;
}

// ---- PolyLineWriter ------------------------------------------------------------------------

namespace {

void put_big_u32(unsigned char* at, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) at[i] = static_cast<unsigned char>(value >> (24 - 8 * i));
}

void put_little_u32(unsigned char* at, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) at[i] = static_cast<unsigned char>(value >> (8 * i));
}

void put_little_f64(unsigned char* at, double value) {
    const auto bits = std::bit_cast<std::uint64_t>(value);
    for (int i = 0; i < 8; ++i) at[i] = static_cast<unsigned char>(bits >> (8 * i));
}

// shapelib's MIN and MAX, in their order: the bound first.
double low_of(double bound, double v) { return bound < v ? bound : v; }
double high_of(double bound, double v) { return bound > v ? bound : v; }

// A file written front to back through a buffer.
class BufferedOutput {
public:
    explicit BufferedOutput(const std::filesystem::path& path) : out_(path, std::ios::binary | std::ios::trunc) {
        buffer_.reserve(kBuffer);
    }
    bool is_open() const { return out_.is_open(); }

    void put(const unsigned char* bytes, std::size_t count) {
        if (buffer_.size() + count > kBuffer) flush();
        if (count > kBuffer) {
            out_.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(count));
            return;
        }
        buffer_.insert(buffer_.end(), bytes, bytes + count);
    }
    void flush() {
        out_.write(reinterpret_cast<const char*>(buffer_.data()), static_cast<std::streamsize>(buffer_.size()));
        buffer_.clear();
    }
    // Flushes, writes `header` over the file's first bytes and closes it; false if anything failed.
    bool close_with_header(std::span<const unsigned char> header) {
        flush();
        out_.seekp(0);
        out_.write(reinterpret_cast<const char*>(header.data()), static_cast<std::streamsize>(header.size()));
        out_.close();
        return !out_.fail();
    }
    bool good() const { return out_.good(); }

private:
    static constexpr std::size_t kBuffer = std::size_t{1} << 20;
    std::ofstream out_;
    std::vector<unsigned char> buffer_;
};

constexpr std::uint32_t kPolyLine = 3;
constexpr std::size_t kHeader = 100;

}  // namespace

struct PolyLineWriter::State {
    State(const std::filesystem::path& shp, const std::filesystem::path& shx) : shp_file(shp), shx_file(shx) {}
    BufferedOutput shp_file, shx_file;
    std::string shown_as;
    std::uint64_t shp_size = kHeader;  // bytes so far
    std::uint64_t records = 0;
    std::array<double, 4> box{};      // x low, y low, x high, y high
    std::vector<unsigned char> record;
};

PolyLineWriter::PolyLineWriter(const std::string& shp, std::string shown_as) {
    const std::filesystem::path shp_path(shp);
    state_ = std::make_unique<State>(shp_path, std::filesystem::path(shp_path).replace_extension(".shx"));
    state_->shown_as = std::move(shown_as);
    if (!state_->shp_file.is_open() || !state_->shx_file.is_open()) {
        throw OutputError("cannot write '" + state_->shown_as + "': " + std::strerror(errno));
    }
    // Room for the headers, which hold the files' lengths and the box: finish() writes them
    // over it once the records are written.
    const std::array<unsigned char, kHeader> header_room{};
    state_->shp_file.put(header_room.data(), header_room.size());
    state_->shx_file.put(header_room.data(), header_room.size());
}

PolyLineWriter::PolyLineWriter(PolyLineWriter&&) noexcept = default;
PolyLineWriter& PolyLineWriter::operator=(PolyLineWriter&&) noexcept = default;
PolyLineWriter::~PolyLineWriter() = default;

bool PolyLineWriter::add(std::span<const std::uint32_t> part_starts, std::span<const Point> xy) {
    State& s = *state_;
    const bool null = part_starts.empty();
    // Content: the shape type; then the box, the part and point counts, the parts and the points.
    const std::size_t content = null ? 4 : 44 + 4 * part_starts.size() + 16 * xy.size();
    if (s.shp_size + 8 + content > std::numeric_limits<std::uint32_t>::max()) return false;
    std::vector<unsigned char>& record = s.record;
    record.resize(8 + content);
    put_big_u32(&record[0], static_cast<std::uint32_t>(s.records + 1));
    put_big_u32(&record[4], static_cast<std::uint32_t>(content / 2));
    put_little_u32(&record[8], null ? 0 : kPolyLine);
    if (s.records == 0) {
        s.box = null ? std::array<double, 4>{} : std::array<double, 4>{xy[0].x, xy[0].y, xy[0].x, xy[0].y};
    }
    if (!null) {
        std::array<double, 4> box{xy[0].x, xy[0].y, xy[0].x, xy[0].y};
        unsigned char* at = &record[52 + 4 * part_starts.size()];
        for (const Point& p : xy) {
            box = {low_of(box[0], p.x), low_of(box[1], p.y), high_of(box[2], p.x), high_of(box[3], p.y)};
            s.box = {low_of(s.box[0], p.x), low_of(s.box[1], p.y), high_of(s.box[2], p.x), high_of(s.box[3], p.y)};
            put_little_f64(at, p.x);
            put_little_f64(at + 8, p.y);
            at += 16;
        }
        for (int i = 0; i < 4; ++i) put_little_f64(&record[12 + 8 * i], box[static_cast<std::size_t>(i)]);
        put_little_u32(&record[44], static_cast<std::uint32_t>(part_starts.size()));
        put_little_u32(&record[48], static_cast<std::uint32_t>(xy.size()));
        for (std::size_t k = 0; k < part_starts.size(); ++k) put_little_u32(&record[52 + 4 * k], part_starts[k]);
    }
    std::array<unsigned char, 8> index{};
    put_big_u32(&index[0], static_cast<std::uint32_t>(s.shp_size / 2));
    put_big_u32(&index[4], static_cast<std::uint32_t>(content / 2));
    s.shp_file.put(record.data(), record.size());
    s.shx_file.put(index.data(), index.size());
    s.shp_size += record.size();
    ++s.records;
    if (!s.shp_file.good() || !s.shx_file.good()) throw OutputError("cannot write '" + s.shown_as + "': " + std::strerror(errno));
    return true;
}

void PolyLineWriter::finish() {
    State& s = *state_;
    // The header: file code 9994 and the length in 16-bit words (big-endian), version 1000, the
    // shape type, the box, and Z and M ranges of 0 (little-endian).
    std::array<unsigned char, kHeader> header{};
    put_big_u32(&header[0], 9994);
    put_big_u32(&header[24], static_cast<std::uint32_t>(s.shp_size / 2));
    put_little_u32(&header[28], 1000);
    put_little_u32(&header[32], kPolyLine);
    for (int i = 0; i < 4; ++i) put_little_f64(&header[36 + 8 * i], s.box[static_cast<std::size_t>(i)]);
    const bool shp_written = s.shp_file.close_with_header(header);
    put_big_u32(&header[24], static_cast<std::uint32_t>((kHeader + 8 * s.records) / 2));
    const bool shx_written = s.shx_file.close_with_header(header);
    if (!shp_written || !shx_written) throw OutputError("cannot write '" + s.shown_as + "': " + std::strerror(errno));
}

void refuse_non_finite(const ShapeRecord& record, const std::function<std::string()>& label) {
    const std::span<const std::uint32_t> parts = record.part_starts;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const std::size_t part_first = parts[k], part_end = k + 1 < parts.size() ? parts[k + 1] : record.xy.size();
        for (std::size_t v = part_first; v < part_end; ++v) {
            const Point p = record.xy[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
                throw InputError(label() + ": vertex " + std::to_string(v - part_first) + " has a non-finite coordinate (" +
                                 std::to_string(p.x) + ", " + std::to_string(p.y) + ")");
            }
        }
    }
}

std::int64_t modified_ns(const std::string& path) {
    std::error_code error;
    const auto time = std::filesystem::last_write_time(path, error);
    if (error) return -1;
    return std::chrono::duration_cast<std::chrono::nanoseconds>(time.time_since_epoch()).count();
}

map::MapData read_shapefile_lines(const std::string& path, const std::string& layer, std::uint64_t first, std::uint64_t end) {
    std::optional<ShapeReader> reader = ShapeReader::open(path, first, end);
    auto unreadable = [&] {
        return InputError("'" + path + "': records " + std::to_string(first) + " to " + std::to_string(end) +
                          " are not the plain PolyLine records they were when the map was read");
    };
    if (!reader || end > reader->records()) throw unreadable();
    map::MapData part;
    while (const ShapeRecord* record = reader->next()) {
        if (!record->z.empty()) throw unreadable();
        refuse_non_finite(*record, [&] { return "'" + path + "', layer '" + layer + "', feature " + std::to_string(reader->fid()); });
        const std::span<const std::uint32_t> parts = record->part_starts;
        for (std::size_t k = 0; k < parts.size(); ++k) {
            const std::size_t part_first = parts[k], part_end = k + 1 < parts.size() ? parts[k + 1] : record->xy.size();
            if (part.vertices.size() + (part_end - part_first) >= std::numeric_limits<std::uint32_t>::max() / 2) throw unreadable();
            part.add_chain(record->xy.subspan(part_first, part_end - part_first));
        }
    }
    if (reader->failed()) throw unreadable();
    return part;
}

}  // namespace toposimp::io
