#include "io/ogr/field_text.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace toposimp::io {
namespace {

void append_two_digits(std::string& out, int value) {
    out += static_cast<char>('0' + value / 10);
    out += static_cast<char>('0' + value % 10);
}

}  // namespace

std::string iso_date_time(const OGRFeature& feature, int field, OGRFieldType type) {
    int year = 0, month = 0, day = 0, hour = 0, minute = 0, zone = 0;
    float second = 0;
    feature.GetFieldAsDateTime(field, &year, &month, &day, &hour, &minute, &second, &zone);
    std::string text;
    if (type != OFTTime) {
        char date[16];
        std::snprintf(date, sizeof date, "%04d-", year);
        text += date;
        append_two_digits(text, month);
        text += '-';
        append_two_digits(text, day);
    }
    if (type != OFTDate) {
        if (type == OFTDateTime) text += 'T';
        append_two_digits(text, hour);
        text += ':';
        append_two_digits(text, minute);
        text += ':';
        const int whole = static_cast<int>(second);
        append_two_digits(text, whole);
        const int millis = static_cast<int>(std::lround((second - static_cast<float>(whole)) * 1000.0));
        if (millis > 0 && millis < 1000) {
            char fraction[16];
            std::snprintf(fraction, sizeof fraction, ".%03d", millis);
            text += fraction;
        }
        // GDAL time zone flag: 100 = UTC, each step is 15 minutes; 0/1 = unknown/local.
        if (zone == 100) {
            text += 'Z';
        } else if (zone > 1) {
            const int offset = (zone - 100) * 15;
            text += offset < 0 ? '-' : '+';
            append_two_digits(text, std::abs(offset) / 60);
            text += ':';
            append_two_digits(text, std::abs(offset) % 60);
        }
    }
    return text;
}

}  // namespace toposimp::io
