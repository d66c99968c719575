// Key tables: a struct's JSON keys declared once, as a tuple of (key, member) pairs, from which the
// struct is written to JSON and read back (docs/architecture.md, "One report model").
//
//     template <> inline constexpr auto kKeys<FrustumStats> = std::tuple{
//         json::key("objects_in", &FrustumStats::objectsIn), ...};
//     json::write(frustum)               -> {"objects_in": ..., ...} in the table's order
//     json::read(j, &frustum)            <- the same keys back (merge, budgets, the page)
//     json::keyNames(kKeys<FrustumStats>) the key list a test checks against the report's schema
//
// A member is written as itself: integers, booleans and strings as they are, a double as a number or
// null when it is not finite (JSON has no NaN or infinity), a vector or array element by element,
// an optional as null when empty, and a struct that has a table of its own as an object. A key whose
// value is derived (a share, a name from an enum, a null that stands for "none") is a `derived`
// entry: a function of the whole struct, written but never read back.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace va::json {

using OJson = nlohmann::ordered_json;

// One entry of a table: a key and the member it holds.
template <class T, class M>
struct Key {
    const char *name;
    M T::*member;
};
template <class T, class M>
constexpr Key<T, M> key(const char *name, M T::*member) {
    return {name, member};
}

// A derived key: written from the whole struct, not read back.
template <class T>
struct Derived {
    const char *name;
    OJson (*value)(const T &);
};
template <class T>
constexpr Derived<T> derived(const char *name, OJson (*value)(const T &)) {
    return {name, value};
}

// The default table of a struct (specialised next to the report's other tables); `void` when it has none.
template <class T>
inline constexpr auto kKeys = 0;

template <class T>
concept HasKeys = !std::is_same_v<std::remove_cv_t<decltype(kKeys<T>)>, int>;

template <class V> struct IsVector : std::false_type {};
template <class V, class A> struct IsVector<std::vector<V, A>> : std::true_type {};
template <class V> struct IsStdArray : std::false_type {};
template <class V, size_t N> struct IsStdArray<std::array<V, N>> : std::true_type {};
template <class V> struct IsOptional : std::false_type {};
template <class V> struct IsOptional<std::optional<V>> : std::true_type {};

template <class Table, class T> void writeInto(OJson &j, const T &t, const Table &table);
template <class Table, class T> void readFrom(const OJson &j, T *t, const Table &table);

// One value as JSON (see the header comment for the rules).
template <class V>
OJson value(const V &v) {
    if constexpr (HasKeys<V>) {
        OJson j = OJson::object();
        writeInto(j, v, kKeys<V>);
        return j;
    } else if constexpr (std::is_floating_point_v<V>) {
        return std::isfinite(v) ? OJson(v) : OJson(nullptr);
    } else if constexpr (IsVector<V>::value || IsStdArray<V>::value || std::is_array_v<V>) {
        OJson a = OJson::array();
        for (const auto &e : v) a.push_back(value(e));
        return a;
    } else if constexpr (IsOptional<V>::value) {
        return v ? value(*v) : OJson(nullptr);
    } else {
        return OJson(v);
    }
}

// Writes every key of `table` into the object j, in the table's order.
template <class Table, class T>
void writeInto(OJson &j, const T &t, const Table &table) {
    std::apply(
        [&](const auto &...entry) {
            auto one = [&](const auto &e) {
                if constexpr (requires { e.member; }) j[e.name] = value(t.*(e.member));
                else j[e.name] = e.value(t);
            };
            (one(entry), ...);
        },
        table);
}

// t as a JSON object, by its default table or by `table`.
template <class T>
OJson write(const T &t) {
    return value(t);
}
template <class T, class Table>
OJson write(const T &t, const Table &table) {
    OJson j = OJson::object();
    writeInto(j, t, table);
    return j;
}

// Reads one value back; a missing key or a value of another type leaves `out` as it was and returns
// false. null reads as NaN into a double and as empty into an optional.
template <class V>
bool readValue(const OJson &j, V *out) {
    if constexpr (HasKeys<V>) {
        if (!j.is_object()) return false;
        readFrom(j, out, kKeys<V>);
        return true;
    } else if constexpr (std::is_floating_point_v<V>) {
        if (j.is_null()) *out = std::numeric_limits<V>::quiet_NaN();
        else if (j.is_number()) *out = j.get<V>();
        else return false;
        return true;
    } else if constexpr (std::is_same_v<V, bool>) {
        if (!j.is_boolean()) return false;
        *out = j.get<bool>();
        return true;
    } else if constexpr (std::is_integral_v<V>) {
        if (std::is_unsigned_v<V> ? !j.is_number_unsigned() : !j.is_number_integer()) return false;
        *out = j.get<V>();
        return true;
    } else if constexpr (std::is_same_v<V, std::string>) {
        if (!j.is_string()) return false;
        *out = j.get<std::string>();
        return true;
    } else if constexpr (IsVector<V>::value) {
        if (!j.is_array()) return false;
        V v(j.size());
        for (size_t i = 0; i < j.size(); ++i)
            if (!readValue(j[i], &v[i])) return false;
        *out = std::move(v);
        return true;
    } else if constexpr (IsStdArray<V>::value || std::is_array_v<V>) {
        if (!j.is_array() || j.size() != std::size(*out)) return false;
        for (size_t i = 0; i < j.size(); ++i)
            if (!readValue(j[i], &(*out)[i])) return false;
        return true;
    } else if constexpr (IsOptional<V>::value) {
        if (j.is_null()) {
            out->reset();
            return true;
        }
        typename V::value_type v{};
        if (!readValue(j, &v)) return false;
        *out = std::move(v);
        return true;
    } else {
        static_assert(sizeof(V) == 0, "json::readValue: no rule for this member type");
    }
}

// Reads every member key of `table` that j has; derived keys are skipped.
template <class Table, class T>
void readFrom(const OJson &j, T *t, const Table &table) {
    if (!j.is_object()) return;
    std::apply(
        [&](const auto &...entry) {
            auto one = [&](const auto &e) {
                if constexpr (requires { e.member; }) {
                    auto it = j.find(e.name);
                    if (it != j.end()) readValue(*it, &(t->*(e.member)));
                }
            };
            (one(entry), ...);
        },
        table);
}
template <class T>
T read(const OJson &j) {
    T t{};
    readFrom(j, &t, kKeys<T>);
    return t;
}

// The keys of a table, in order.
template <class Table>
std::vector<std::string> keyNames(const Table &table) {
    std::vector<std::string> names;
    std::apply([&](const auto &...entry) { (names.push_back(entry.name), ...); }, table);
    return names;
}

}  // namespace va::json
