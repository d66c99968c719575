// report.html: escaping, value formatting and generic tables (reports/html_parts.h).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "reports/html_parts.h"

namespace va::html {

size_t utf8Length(std::string_view s, size_t i) {
    const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = b(i);
    size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (n == 0 || i + n > s.size()) return 0;
    for (size_t k = 1; k < n; ++k)
        if ((b(i + k) & 0xC0) != 0x80) return 0;
    if (n == 2 && c < 0xC2) return 0;                                   // overlong
    if (n == 3 && c == 0xE0 && b(i + 1) < 0xA0) return 0;               // overlong
    if (n == 3 && c == 0xED && b(i + 1) >= 0xA0) return 0;              // surrogates
    if (n == 4 && ((c == 0xF0 && b(i + 1) < 0x90) || c > 0xF4 || (c == 0xF4 && b(i + 1) >= 0x90))) return 0;
    return n;
}

std::string esc(std::string_view s) {
    std::string o;
    o.reserve(s.size() + 8);
    for (size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        const size_t n = utf8Length(s, i);
        if (n == 0) {
            o += "\xEF\xBF\xBD";
            ++i;
            continue;
        }
        if (n > 1) {
            o.append(s.substr(i, n));
            i += n;
            continue;
        }
        switch (c) {
        case '&': o += "&amp;"; break;
        case '<': o += "&lt;"; break;
        case '>': o += "&gt;"; break;
        case '"': o += "&quot;"; break;
        case '\'': o += "&#39;"; break;
        default:
            if ((c < 0x20 && c != '\t' && c != '\n') || c == 0x7F) o += "\xEF\xBF\xBD";
            else o += char(c);
        }
        ++i;
    }
    return o;
}

std::string slug(std::string_view s) {
    std::string o;
    for (char ch : s) {
        const unsigned char c = static_cast<unsigned char>(ch);
        if (std::isalnum(c) && c < 0x80) o += char(std::tolower(c));
        else if (c == '-' || c == '_') o += char(c);
        else o += '_';
    }
    return o.empty() ? "_" : o;
}

std::string fmtValue(const Json *j) {
    if (!j || j->is_null()) return "—";
    if (j->is_number_integer() || j->is_number_unsigned()) return fmtCount(j->get<double>());
    if (j->is_number()) return fmtReal(j->get<double>());
    if (j->is_boolean()) return j->get<bool>() ? "yes" : "no";
    if (j->is_string()) return esc(j->get<std::string>());
    if (j->is_array()) {
        std::string o;
        for (const Json &e : *j) {
            if (!o.empty()) o += ", ";
            o += e.is_structured() ? std::string("…") : fmtValue(&e);
        }
        return "[" + o + "]";
    }
    return "…";
}

std::string fx(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    return buf;
}

std::string label(std::string_view key) {
    std::string o(key);
    std::replace(o.begin(), o.end(), '_', ' ');
    return esc(o);
}

std::vector<std::string> scalarColumns(const std::vector<const Json *> &rows) {
    std::vector<std::string> cols;
    for (const Json *r : rows)
        if (r && r->is_object())
            for (auto it = r->begin(); it != r->end(); ++it)
                if (!it.value().is_object() &&
                    !(it.value().is_array() && !it.value().empty() && it.value().front().is_structured()) &&
                    std::find(cols.begin(), cols.end(), it.key()) == cols.end())
                    cols.push_back(it.key());
    return cols;
}

std::string rowsTable(const std::vector<const Json *> &rows, const std::string &firstHeader,
                      const std::vector<std::string> &firstColumn) {
    const std::vector<std::string> cols = scalarColumns(rows);
    std::string o = "<div class=\"scroll\"><table><tr>";
    if (!firstColumn.empty()) o += "<th>" + esc(firstHeader) + "</th>";
    for (const std::string &c : cols) o += "<th>" + label(c) + "</th>";
    o += "</tr>";
    for (size_t i = 0; i < rows.size(); ++i) {
        o += "<tr>";
        if (!firstColumn.empty()) o += "<td>" + esc(firstColumn[i]) + "</td>";
        for (const std::string &c : cols) {
            const Json *v = get(rows[i], c);
            o += std::string(v && v->is_number() ? "<td class=\"n\">" : "<td>") + fmtValue(v) + "</td>";
        }
        o += "</tr>";
    }
    return o + "</table></div>";
}

std::string genericJson(const Json *j, int depth) {
    if (!j) return {};
    if (j->is_array()) {
        std::vector<const Json *> rows;
        for (const Json &e : *j)
            if (e.is_object()) rows.push_back(&e);
        if (!rows.empty()) return rowsTable(rows);
        return "<p>" + fmtValue(j) + "</p>";
    }
    if (!j->is_object()) return "<p>" + fmtValue(j) + "</p>";
    std::string scalars, nested;
    for (auto it = j->begin(); it != j->end(); ++it) {
        const Json &v = it.value();
        const bool tableArray = v.is_array() && !v.empty() && v.front().is_object();
        if (!v.is_object() && !tableArray) {
            scalars += "<tr><th>" + label(it.key()) + "</th><td" + (v.is_number() ? " class=\"n\"" : "") + ">" +
                       fmtValue(&v) + "</td></tr>";
            continue;
        }
        // An object whose members are all objects reads best as one table (rows = members).
        bool allObjects = v.is_object() && !v.empty();
        if (v.is_object())
            for (auto m = v.begin(); m != v.end(); ++m) allObjects = allObjects && m.value().is_object();
        nested += "<h4>" + label(it.key()) + "</h4>";
        if (allObjects) {
            std::vector<const Json *> rows;
            std::vector<std::string> names;
            for (auto m = v.begin(); m != v.end(); ++m) {
                rows.push_back(&m.value());
                names.push_back(m.key());
            }
            nested += rowsTable(rows, "name", names);
        } else if (depth < 4) {
            nested += genericJson(&v, depth + 1);
        }
    }
    std::string o;
    if (!scalars.empty()) o += "<div class=\"scroll\"><table>" + scalars + "</table></div>";
    return o + nested;
}

std::string rawInt(const Json *j) {
    if (!j || !j->is_number_integer()) return "—";
    return j->is_number_unsigned() ? std::to_string(j->get<uint64_t>()) : std::to_string(j->get<int64_t>());
}

}  // namespace va::html
