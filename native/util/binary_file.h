// Little-endian binary files of SHGI's own caches (probes/probe_storage, lattice/photon_lattice,
// propagation/propagation_field), and the same format in memory (a photon batch's bytes: any
// std::ostream / std::istream), each opening with a header (magic, version):
// BinaryWriter puts values and arrays as they lie in memory (every supported platform is
// little-endian); BinaryReader reads them back and turns a short read into an IoError naming the
// file and the part it ended inside, so that a truncated file is never read as zeros.
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "util/error.h"

namespace shgi {

class BinaryWriter {
  public:
    explicit BinaryWriter(std::ostream& out) : out_(out) {}
    template <typename T>
    void put(const T& value) {
        out_.write(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    void bytes(const void* data, size_t size) {
        out_.write(static_cast<const char*>(data), std::streamsize(size));
    }
    // A format's header: its 8-byte magic, then its version (u32); BinaryReader::header reads it.
    void header(const char (&magic)[8], uint32_t version) {
        bytes(magic, sizeof(magic));
        put(version);
    }
    // The element count (u64), then the elements.
    template <typename T>
    void array(const std::vector<T>& values) {
        put(uint64_t(values.size()));
        bytes(values.data(), values.size() * sizeof(T));
    }

  private:
    std::ostream& out_;
};

class BinaryReader {
  public:
    // `kind` names the file in messages ("probe file", "lattice file").
    BinaryReader(std::istream& in, const std::string& path, const char* kind)
        : in_(in), path_(path), kind_(kind) {}
    template <typename T>
    T get(const char* what) {
        T value;
        bytes(&value, sizeof(T), what);
        return value;
    }
    void bytes(void* data, size_t size, const char* what) {
        in_.read(static_cast<char*>(data), std::streamsize(size));
        if (size_t(in_.gcount()) != size)
            throw IoError(format_message("cannot read ", kind_, " \"", path_,
                                         "\": it ends inside ", what, " (truncated?)"));
    }
    // What BinaryWriter::header wrote: IoError naming the file when its magic is not `magic`
    // ("is not an SHGI <kind>") or its version is outside [lowest, highest]; the version.
    uint32_t header(const char (&magic)[8], uint32_t lowest, uint32_t highest) {
        char read[sizeof(magic)];
        bytes(read, sizeof(read), "the header");
        if (std::memcmp(read, magic, sizeof(read)) != 0)
            throw IoError(format_message("\"", path_, "\" is not an SHGI ", kind_, " (bad magic)"));
        const uint32_t version = get<uint32_t>("the header");
        if (version < lowest || version > highest)
            throw IoError(format_message(kind_, " \"", path_, "\" has version ", version,
                                         "; this SHGI reads ",
                                         lowest == highest ? "version " : "versions ",
                                         lowest == highest ? "" : format_message(lowest, " to "),
                                         highest));
        return version;
    }
    // What BinaryWriter::array wrote: checked against the bytes left in the file before
    // anything is allocated, so that a damaged count cannot ask for gigabytes.
    template <typename T>
    std::vector<T> array(const char* what) {
        const uint64_t count = get<uint64_t>(what);
        const uint64_t remaining = remaining_bytes();
        if (count > remaining / sizeof(T))
            throw IoError(format_message("cannot read ", kind_, " \"", path_, "\": ", what, " (",
                                         count, " of ", sizeof(T), " bytes) is longer than the ",
                                         remaining, " bytes left (truncated?)"));
        std::vector<T> values(count);
        bytes(values.data(), count * sizeof(T), what);
        return values;
    }
    // Bytes from the stream's position to the end of the file; the position is kept.
    uint64_t remaining_bytes() {
        const std::streampos here = in_.tellg();
        in_.seekg(0, std::ios::end);
        const std::streampos end = in_.tellg();
        in_.seekg(here);
        if (here < 0 || end < here || !in_)
            throw IoError(format_message("cannot find the size of ", kind_, " \"", path_, "\""));
        return uint64_t(end - here);
    }
    const std::string& path() const { return path_; }
    const char* kind() const { return kind_; }

  private:
    std::istream& in_;
    const std::string& path_;
    const char* kind_;
};

}  // namespace shgi
