#include "io/map/gpkg_points.hpp"

#include "io/common/errors.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>

namespace toposimp::io {
namespace {

struct ConnectionCloser {
    void operator()(sqlite3* db) const { sqlite3_close(db); }
};
using Connection = std::unique_ptr<sqlite3, ConnectionCloser>;

struct StatementFinalizer {
    void operator()(sqlite3_stmt* statement) const { sqlite3_finalize(statement); }
};
using Statement = std::unique_ptr<sqlite3_stmt, StatementFinalizer>;

Connection open_read_only(const std::string& path) {
    sqlite3* db = nullptr;
    const int status = sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX, nullptr);
    Connection connection(db);  // closed even when opening failed
    if (status != SQLITE_OK) return nullptr;
    return connection;
}

// `name` as an SQL identifier, in double quotes.
std::string sql_identifier(const std::string& name) {
    std::string text = "\"";
    for (const char c : name) text += c == '"' ? std::string("\"\"") : std::string(1, c);
    return text + "\"";
}

Statement prepare(sqlite3* db, const std::string& sql) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) return nullptr;
    return Statement(statement);
}

// Reads a blob front to back; every read fails past the end.
class BlobReader {
public:
    BlobReader(const unsigned char* data, std::size_t size) : data_(data), size_(size) {}

    bool skip(std::size_t count) {
        if (size_ - at_ < count) return false;
        at_ += count;
        return true;
    }
    bool byte(std::uint8_t& out) {
        if (at_ >= size_) return false;
        out = data_[at_++];
        return true;
    }
    bool u32(bool little_endian, std::uint32_t& out) {
        unsigned char bytes[4];
        if (!take(bytes, 4)) return false;
        out = 0;
        for (int i = 0; i < 4; ++i) out |= std::uint32_t{bytes[little_endian ? i : 3 - i]} << (8 * i);
        return true;
    }
    bool f64(bool little_endian, double& out) {
        unsigned char bytes[8];
        if (!take(bytes, 8)) return false;
        std::uint64_t bits = 0;
        for (int i = 0; i < 8; ++i) bits |= std::uint64_t{bytes[little_endian ? i : 7 - i]} << (8 * i);
        std::memcpy(&out, &bits, sizeof out);
        return true;
    }

private:
    bool take(unsigned char* out, std::size_t count) {
        if (size_ - at_ < count) return false;
        std::memcpy(out, data_ + at_, count);
        at_ += count;
        return true;
    }

    const unsigned char* data_;
    std::size_t size_;
    std::size_t at_ = 0;
};

using Decoded = PointBlob;

// One WKB Point or MultiPoint (ISO codes 1/4 + 1000·Z/M/ZM, or the older 0x80000000 Z and
// 0x40000000 M flags). A point with NaN for both x and y is empty, as OGR reads it.
Decoded decode_wkb(BlobReader& in, std::vector<Point>& out, bool member) {
    std::uint8_t order = 0;
    std::uint32_t type = 0;
    if (!in.byte(order) || order > 1 || !in.u32(order == 1, type)) return Decoded::not_decoded;
    const bool little = order == 1;
    int extra = 0;  // Z and M ordinates after x and y
    if (type & 0x80000000u) ++extra;
    if (type & 0x40000000u) ++extra;
    if (type & 0x20000000u) return Decoded::not_decoded;  // an EWKB SRID follows: not GeoPackage
    type &= 0x0fffffffu;
    if (type >= 1000 && type < 4000) {
        extra += type >= 3000 ? 2 : 1;
        type %= 1000;
    }
    if (type == 1) {
        double x = 0, y = 0, ignored = 0;
        if (!in.f64(little, x) || !in.f64(little, y)) return Decoded::not_decoded;
        for (int i = 0; i < extra; ++i) {
            if (!in.f64(little, ignored)) return Decoded::not_decoded;
        }
        if (std::isnan(x) && std::isnan(y)) return Decoded::ok;
        if (!std::isfinite(x) || !std::isfinite(y)) return Decoded::non_finite;
        out.push_back({x, y});
        return Decoded::ok;
    }
    if (type == 4 && !member) {
        std::uint32_t count = 0;
        if (!in.u32(little, count)) return Decoded::not_decoded;
        for (std::uint32_t i = 0; i < count; ++i) {
            if (const Decoded part = decode_wkb(in, out, true); part != Decoded::ok) return part;
        }
        return Decoded::ok;
    }
    return Decoded::not_decoded;
}

// A GeoPackage geometry blob: "GP", version 0, flags (byte order of the header, envelope kind,
// empty, extended), srs_id, envelope, WKB.
Decoded decode_blob(const unsigned char* data, std::size_t size, std::vector<Point>& out) {
    if (size < 8 || data[0] != 'G' || data[1] != 'P' || data[2] != 0) return Decoded::not_decoded;
    const std::uint8_t flags = data[3];
    if (flags & 0x20) return Decoded::not_decoded;  // ExtendedGeoPackageBinary
    if (flags & 0x10) return Decoded::ok;           // empty geometry
    static constexpr std::size_t kEnvelopeBytes[] = {0, 32, 48, 48, 64};
    const unsigned envelope = (flags >> 1) & 7u;
    if (envelope > 4) return Decoded::not_decoded;
    BlobReader in(data, size);
    if (!in.skip(8 + kEnvelopeBytes[envelope])) return Decoded::not_decoded;
    return decode_wkb(in, out, false);
}

// The rows with from <= FID < to (to: none, up to the last; all rows when `range` is false), in
// FID order.
std::optional<std::vector<Point>> read_rows(const GpkgTable& table, bool range, std::int64_t from, std::optional<std::int64_t> to,
                                            std::size_t expected) {
    Connection db = open_read_only(table.path);
    if (!db) return std::nullopt;
    const std::string fid = sql_identifier(table.fid_column);
    std::string sql = "SELECT " + fid + ", " + sql_identifier(table.geometry_column) + " FROM " + sql_identifier(table.table);
    if (range) sql += " WHERE " + fid + " >= ?1" + (to ? " AND " + fid + " < ?2" : "");
    sql += " ORDER BY " + fid;
    Statement statement = prepare(db.get(), sql);
    if (!statement) return std::nullopt;
    if (range) {
        sqlite3_bind_int64(statement.get(), 1, from);
        if (to) sqlite3_bind_int64(statement.get(), 2, *to);
    }
    std::vector<Point> points;
    points.reserve(expected);
    int status = SQLITE_ROW;
    while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
        const int kind = sqlite3_column_type(statement.get(), 1);
        if (kind == SQLITE_NULL) continue;
        if (kind != SQLITE_BLOB) return std::nullopt;
        const auto* data = static_cast<const unsigned char*>(sqlite3_column_blob(statement.get(), 1));
        const auto size = static_cast<std::size_t>(sqlite3_column_bytes(statement.get(), 1));
        switch (decode_blob(data, size, points)) {
            case Decoded::ok: break;
            case Decoded::not_decoded: return std::nullopt;
            case Decoded::non_finite:
                throw InputError("'" + table.path + "', layer '" + table.table + "', feature " +
                                 std::to_string(sqlite3_column_int64(statement.get(), 0)) +
                                 ": control point has a non-finite coordinate");
        }
    }
    if (status != SQLITE_DONE) return std::nullopt;
    return points;
}

}  // namespace

PointBlob decode_point_blob(const unsigned char* data, std::size_t size, std::vector<Point>& out) {
    return decode_blob(data, size, out);
}

std::optional<std::vector<Point>> read_gpkg_points(const GpkgTable& table, unsigned threads) {
    if (table.fid_column.empty() || table.geometry_column.empty()) return std::nullopt;
    std::int64_t first = 0, last = -1;
    {
        Connection db = open_read_only(table.path);
        if (!db) return std::nullopt;
        // Two subqueries: SQLite looks a lone MIN or MAX up in the key's b-tree, but scans the
        // whole table for "SELECT MIN(fid), MAX(fid)".
        const std::string fid = sql_identifier(table.fid_column), from = " FROM " + sql_identifier(table.table);
        Statement bounds = prepare(db.get(), "SELECT (SELECT MIN(" + fid + ")" + from + "), (SELECT MAX(" + fid + ")" + from + ")");
        if (!bounds || sqlite3_step(bounds.get()) != SQLITE_ROW) return std::nullopt;
        if (sqlite3_column_type(bounds.get(), 0) == SQLITE_NULL) return std::vector<Point>{};  // no rows
        first = sqlite3_column_int64(bounds.get(), 0);
        last = sqlite3_column_int64(bounds.get(), 1);
    }
    // FIDs say nothing of how many rows there are (FIDs 1 and 2^62: two rows), so no count is
    // taken from them: reservations are bounded by what the file can hold (a point's row takes
    // a blob of at least 29 bytes), and the span is computed without signed overflow (FIDs may
    // run from INT64_MIN to INT64_MAX; issue 29).
    std::error_code error;
    const std::uintmax_t bytes = std::filesystem::file_size(table.path, error);
    const std::uint64_t most_rows = error ? 0 : bytes / 29 + 1;
    const std::uint64_t gaps = static_cast<std::uint64_t>(last) - static_cast<std::uint64_t>(first);  // last - first, exactly
    auto reservation = [most_rows](std::uint64_t fids) { return static_cast<std::size_t>(std::min(fids, most_rows)); };
    // Below this many FIDs one connection is as quick as starting several.
    constexpr std::uint64_t kSplitFrom = 1 << 16;
    if (threads <= 1 || gaps < kSplitFrom) return read_rows(table, false, 0, 0, reservation(gaps + 1));
    std::vector<std::future<std::optional<std::vector<Point>>>> parts;
    const std::uint64_t share = gaps / threads;
    for (unsigned t = 0; t < threads; ++t) {
        // (Modular: first + share·t never passes last; the bounds are FIDs again.)
        const auto from = static_cast<std::int64_t>(static_cast<std::uint64_t>(first) + share * t);
        const std::optional<std::int64_t> to =
            t + 1 == threads ? std::nullopt : std::optional(static_cast<std::int64_t>(static_cast<std::uint64_t>(first) + share * (t + 1)));
        // (The first part reserves room for all: the others are then appended to it, not all
        // copied into a new array — 160 MB for 10 M points, 0.1 s.)
        const std::size_t expected = reservation(t == 0 ? gaps + 1 : t + 1 == threads ? gaps - share * t + 1 : share);
        parts.push_back(std::async(std::launch::async, [&table, from, to, expected] {
            return read_rows(table, true, from, to, expected);
        }));
    }
    std::vector<std::optional<std::vector<Point>>> read;
    for (auto& part : parts) read.push_back(part.get());  // rethrows a part's InputError
    std::size_t total = 0;
    for (const auto& part : read) {
        if (!part) return std::nullopt;
        total += part->size();
    }
    std::vector<Point> points = std::move(*read.front());
    points.reserve(total);  // (room already there, unless the reservation was bounded by the file's size)
    for (std::size_t t = 1; t < read.size(); ++t) {
        points.insert(points.end(), read[t]->begin(), read[t]->end());
        read[t].reset();  // the copy and the parts never all live at once
    }
    return points;
}

}  // namespace toposimp::io
