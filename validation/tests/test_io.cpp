// Surface files: exact round trips, other tools' PLY, and clear errors with
// nothing left behind for anything malformed.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>

#include "test_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/io.hpp"

namespace tetiso {
namespace {

namespace fs = std::filesystem;

class Files : public ::testing::Test {
protected:
    fs::path at(const std::string& name) const { return scratch_.at(name); }
    void write_text(const fs::path& path, const std::string& text) const { std::ofstream(path, std::ios::binary) << text; }
    std::size_t files() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(scratch_.path()), fs::directory_iterator())); }
    std::string error_of(const fs::path& path) const {
        try {
            read_piece(path);
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    }
    test::ScratchDirectory scratch_{"tetiso_io"};
};

TEST_F(Files, RoundTripsAreExact) {
    // Two domains, so some vertices carry the locked flag.
    const Lattice lattice(20);
    const Decomposition two(lattice, 2);
    const Piece piece = extract(two.make_domain(1, *make_field("gyroid")), 0.0f);
    ASSERT_GT(std::count(piece.flags.begin(), piece.flags.end(), kLocked), 0);
    for (const char* name : {"s.ply", "s.vtp", "S.PLY"}) {
        write_piece(piece, at(name));
        const Piece back = read_piece(at(name));
        EXPECT_EQ(back.key, piece.key) << name;
        EXPECT_EQ(back.flags, piece.flags) << name;
        EXPECT_TRUE(test::same_bits(back.x, piece.x) && test::same_bits(back.y, piece.y) && test::same_bits(back.z, piece.z)) << name;
        EXPECT_EQ(back.triangles, piece.triangles) << name;
    }
    // Both keep each triangle's error bound, bit for bit; a piece without
    // bounds reads back without them.
    Piece bounded = piece;
    bounded.error.resize(bounded.triangle_count());
    for (std::size_t t = 0; t < bounded.error.size(); ++t) bounded.error[t] = 0.001f * static_cast<float>(t % 97);
    for (const char* name : {"bounded.vtp", "bounded.ply"}) {
        write_piece(bounded, at(name));
        const Piece back = read_piece(at(name));
        EXPECT_TRUE(test::same_bits(back.error, bounded.error)) << name;
        EXPECT_EQ(back.triangles, bounded.triangles) << name;
        EXPECT_TRUE(read_piece(at(std::string("s") + std::filesystem::path(name).extension().string())).error.empty()) << name;
    }
    bounded.error.pop_back();
    for (const char* name : {"mismatched.vtp", "mismatched.ply"}) {
        EXPECT_THROW(write_piece(bounded, at(name)), Error) << name;
        EXPECT_FALSE(std::filesystem::exists(at(name))) << name;
    }

    const Piece empty;
    write_piece(empty, at("empty.vtp"));
    write_piece(empty, at("empty.ply"));
    EXPECT_EQ(read_piece(at("empty.vtp")).triangle_count(), 0u);
    EXPECT_EQ(read_piece(at("empty.ply")).vertex_count(), 0u);
}

TEST_F(Files, ReadsAsciiPlyFromOtherTools) {
    write_text(at("quad.ply"), "ply\nformat ascii 1.0\ncomment hand made\nelement vertex 4\n"
                               "property double x\nproperty double y\nproperty double z\nproperty uchar red\n"
                               "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
                               "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3\n");
    const Piece quad = read_piece(at("quad.ply"));
    ASSERT_EQ(quad.vertex_count(), 4u);
    EXPECT_EQ(quad.key, (std::vector<EdgeKey>{0, 1, 2, 3}));
    EXPECT_EQ(quad.triangles, (std::vector<std::int32_t>{0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(quad.x[2], 1.0f);
}

// Plain names that other tools give their own data are not tetiso's: MeshLab
// writes a vertex "flags" of VCG state bits (ints far above a byte), and any
// tool may write a "key" or "error_bound" of its own meaning. Read as
// tetiso's, they would lock vertices, fail as "not a byte", or replace keys
// and bounds; they must be skipped like any other property.
TEST_F(Files, OtherToolsDataOfTheSamePlainNamesIsNotTetisos) {
    write_text(at("meshlab.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                  "property float z\nproperty int flags\nproperty uint key_hi\nproperty uint key_lo\n"
                                  "element face 1\nproperty list uchar int vertex_indices\nproperty int flags\n"
                                  "property float error_bound\nend_header\n"
                                  "0 0 0 1073741825 7 7\n1 0 0 1 7 8\n0 1 0 1 7 9\n3 0 1 2 1073741825 -2.5\n");
    const Piece ply = read_piece(at("meshlab.ply"));
    EXPECT_EQ(ply.key, (std::vector<EdgeKey>{0, 1, 2}));
    EXPECT_EQ(ply.flags, (std::vector<std::uint8_t>{0, 0, 0}));
    EXPECT_TRUE(ply.error.empty());
    EXPECT_EQ(ply.triangles, (std::vector<std::int32_t>{0, 1, 2}));

    // The same in VTP: tetiso's arrays renamed to the plain names, which
    // keeps every array's bytes (and so its offsets) as they were.
    const Lattice lattice(20);
    Piece piece = extract(Decomposition(lattice, 2).make_domain(1, *make_field("gyroid")), 0.0f);
    ASSERT_GT(std::count(piece.flags.begin(), piece.flags.end(), kLocked), 0);
    piece.error.assign(piece.triangle_count(), 0.5f);
    write_piece(piece, at("own.vtp"));
    std::string vtp = test::read_bytes(at("own.vtp"));
    for (const std::string name : {"key", "flags", "error_bound"}) {
        const std::string ours = "Name=\"tetiso_" + name + "\"";
        ASSERT_NE(vtp.find(ours), std::string::npos) << name;
        vtp.replace(vtp.find(ours), ours.size(), "Name=\"" + name + "\"");
    }
    write_text(at("plain.vtp"), vtp);
    const Piece plain = read_piece(at("plain.vtp"));
    ASSERT_EQ(plain.vertex_count(), piece.vertex_count());
    for (std::size_t v = 0; v < plain.vertex_count(); ++v) ASSERT_EQ(plain.key[v], v);
    EXPECT_TRUE(std::all_of(plain.flags.begin(), plain.flags.end(), [](std::uint8_t f) { return f == 0; }));
    EXPECT_TRUE(plain.error.empty());
    EXPECT_EQ(plain.triangles, piece.triangles);
}

TEST_F(Files, MalformedFilesGetErrorsNamingTheFile) {
    const Lattice lattice(8);
    const Decomposition one(lattice, 1);
    write_piece(extract(one.make_domain(0, *make_field("sphere")), 2.0f), at("good.ply"));
    const std::string bytes = test::read_bytes(at("good.ply"));

    write_text(at("cut.ply"), bytes.substr(0, bytes.size() - 7));
    EXPECT_NE(error_of(at("cut.ply")).find("cut.ply: file ends inside face"), std::string::npos) << error_of(at("cut.ply"));

    std::string huge = bytes;
    huge.replace(huge.find("element face"), std::string("element face").size(), "element face 99999999999 ");
    write_text(at("huge.ply"), huge);
    EXPECT_NE(error_of(at("huge.ply")).find("more than the file can hold"), std::string::npos) << error_of(at("huge.ply"));

    write_text(at("index.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    EXPECT_NE(error_of(at("index.ply")).find("refers to vertex 7"), std::string::npos) << error_of(at("index.ply"));

    write_text(at("nan.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                              "property float z\nend_header\nnan 0 0\n");
    EXPECT_FALSE(error_of(at("nan.ply")).empty());

    // Numbers that would be undefined as integers: a fractional index, a
    // NaN flag, a list length of -1.
    const std::string ascii_head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                   "property float z\nproperty float tetiso_flags\nelement face 1\n"
                                   "property list int float vertex_indices\nend_header\n";
    write_text(at("fraction.ply"), ascii_head + "0 0 0 0\n1 0 0 0\n0 1 0 0\n3 0 1 1.5\n");
    EXPECT_NE(error_of(at("fraction.ply")).find("vertex index 1.5"), std::string::npos) << error_of(at("fraction.ply"));
    write_text(at("flag.ply"), ascii_head + "0 0 0 nan\n1 0 0 0\n0 1 0 0\n3 0 1 2\n");
    EXPECT_NE(error_of(at("flag.ply")).find("vertex 0 has tetiso_flags nan"), std::string::npos) << error_of(at("flag.ply"));
    write_text(at("length.ply"), ascii_head + "0 0 0 0\n1 0 0 0\n0 1 0 0\n-1 0 1 2\n");
    EXPECT_NE(error_of(at("length.ply")).find("not a whole number of at least 3"), std::string::npos)
        << error_of(at("length.ply"));

    // VTP attributes that are not counts, and offsets past the end.
    write_piece(extract(one.make_domain(0, *make_field("sphere")), 2.0f), at("good.vtp"));
    const std::string vtp = test::read_bytes(at("good.vtp"));
    const auto vtp_with = [&](const std::string& find, const std::string& replace) {
        std::string text = vtp;
        text.replace(text.find(find), find.size(), replace);
        return text;
    };
    write_text(at("offset.vtp"), vtp_with("offset=\"0\"", "offset=\"zero\""));
    EXPECT_NE(error_of(at("offset.vtp")).find("offset is not a count: \"zero\""), std::string::npos) << error_of(at("offset.vtp"));
    write_text(at("far.vtp"), vtp_with("offset=\"0\"", "offset=\"18446744073709551615\""));
    EXPECT_NE(error_of(at("far.vtp")).find("shorter than its offsets say"), std::string::npos) << error_of(at("far.vtp"));
    write_text(at("keytype.vtp"), vtp_with("type=\"UInt64\" Name=\"tetiso_key\"", "type=\"Float64\" Name=\"tetiso_key\""));
    EXPECT_NE(error_of(at("keytype.vtp")).find("tetiso_key array is Float64, not UInt64"), std::string::npos)
        << error_of(at("keytype.vtp"));
    write_text(at("points.vtp"), vtp_with("NumberOfPoints=\"", "NumberOfPoints=\"-"));
    EXPECT_NE(error_of(at("points.vtp")).find("NumberOfPoints is not a count"), std::string::npos) << error_of(at("points.vtp"));
    Piece bad_bound = extract(one.make_domain(0, *make_field("sphere")), 2.0f);
    bad_bound.error.assign(bad_bound.triangle_count(), 0.0f);
    bad_bound.error[5] = -1.0f;
    write_piece(bad_bound, at("bound.vtp"));
    EXPECT_NE(error_of(at("bound.vtp")).find("bound.vtp: tetiso_error_bound of polygon 5 is not a finite non-negative float"),
              std::string::npos)
        << error_of(at("bound.vtp"));
    write_piece(bad_bound, at("bound.ply"));
    EXPECT_NE(error_of(at("bound.ply")).find("bound.ply: face 5 has tetiso_error_bound -1.000000, not a finite non-negative float"),
              std::string::npos)
        << error_of(at("bound.ply"));

    write_text(at("text.vtp"), "<VTKFile type=\"UnstructuredGrid\"></VTKFile>");
    EXPECT_NE(error_of(at("text.vtp")).find("not a VTK XML PolyData"), std::string::npos);
    write_text(at("junk.ply"), "hello");
    EXPECT_NE(error_of(at("junk.ply")).find("junk.ply"), std::string::npos);
    EXPECT_NE(error_of(at("missing.ply")).find("cannot open"), std::string::npos);
    EXPECT_NE(error_of(at("mesh.obj")).find("unknown surface format"), std::string::npos);
}

TEST_F(Files, FailedWritesLeaveNothingBehind) {
    const Piece piece = test::lattice_surface(8, 1, "sphere");
    EXPECT_THROW(write_piece(piece, at("no/such/dir/s.ply")), Error);
    EXPECT_THROW(write_piece(piece, at("s.stl")), Error);
    // An existing file survives a failed overwrite: the write goes to a
    // temporary name first, and here it cannot be renamed over a directory.
    fs::create_directory(at("taken.ply"));
    EXPECT_THROW(write_piece(piece, at("taken.ply")), Error);
    EXPECT_TRUE(fs::is_directory(at("taken.ply")));
    EXPECT_EQ(files(), 1u) << "no temporary file may be left";
}

// Several outputs of one command succeed or fail together: a failure in the
// second (a full disk under the report) leaves neither, nor a temporary.
TEST_F(Files, OutputsOfOneCommandSucceedOrFailTogether) {
    const Piece piece = test::lattice_surface(8, 1, "sphere");
    {
        OutputFiles output;
        write_piece(piece, at("s.ply"), output);
        EXPECT_FALSE(fs::exists(at("s.ply"))) << "an output appeared before the others were written";
        EXPECT_THROW(output.add(at("r.json"), [](const fs::path& temporary) {
            throw Error(temporary.string() + ": cannot write: No space left on device");
        }), Error);
    }
    EXPECT_EQ(files(), 0u);
    try {
        OutputFiles output;
        output.add(at("r.json"), [](const fs::path& temporary) { throw Error(temporary.string() + ": cannot write"); });
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), at("r.json").string() + ": cannot write") << "the error names the temporary";
    }
    OutputFiles output;
    write_piece(piece, at("s.ply"), output);
    write_piece(piece, at("t.vtp"), output);
    output.commit();
    EXPECT_EQ(files(), 2u);
    EXPECT_EQ(read_piece(at("s.ply")).key, piece.key);
}

// What is at an output's path and is not a regular file is never replaced:
// a pipe (or a device) is refused, a link is written through.
TEST_F(Files, OutputsNeverReplaceWhatIsNotARegularFile) {
    const Piece piece = test::lattice_surface(8, 1, "sphere");
    ASSERT_EQ(::mkfifo(at("pipe.ply").c_str(), 0600), 0);
    EXPECT_THROW(write_piece(piece, at("pipe.ply")), Error);
    EXPECT_EQ(fs::status(at("pipe.ply")).type(), fs::file_type::fifo);
    fs::create_directory(at("real"));
    fs::create_symlink("real/s.ply", at("link.ply"));
    write_piece(piece, at("link.ply"));
    EXPECT_TRUE(fs::is_symlink(at("link.ply")));
    EXPECT_EQ(read_piece(at("real/s.ply")).key, piece.key);
    EXPECT_EQ(files(), 3u);
}

// Two outputs of one command that are one file (through a link, a hard link
// or "..") would replace each other at commit: the second is refused, and
// nothing is left.
TEST_F(Files, OneFileIsNeverTwoOutputs) {
    const Piece piece = test::lattice_surface(8, 1, "sphere");
    write_piece(piece, at("s.ply"));
    fs::create_symlink("s.ply", at("link.ply"));
    fs::create_hard_link(at("s.ply"), at("hard.ply"));
    fs::create_directory(at("sub"));
    for (const fs::path& other : {at("link.ply"), at("hard.ply"), at("sub") / ".." / "s.ply", at("s.ply")}) {
        OutputFiles output;
        write_piece(piece, at("s.ply"), output);
        EXPECT_THROW(write_piece(piece, other, output), Error) << other;
    }
    EXPECT_TRUE(detail::same_file(at("s.ply"), at("hard.ply")));
    EXPECT_FALSE(detail::same_file(at("s.ply"), at("t.ply")));
    EXPECT_TRUE(detail::same_file(at("t.ply"), at("sub") / ".." / "t.ply")) << "neither exists: by resolved path";
    EXPECT_EQ(files(), 4u) << "a temporary was left";
}

// Temporaries are created exclusively, each under a name of its own, and
// gone once committed or discarded.
TEST_F(Files, TemporariesAreNewFiles) {
    const fs::path first = detail::create_temporary(at("s.ply"), false, at("s.ply"));
    const fs::path second = detail::create_temporary(at("s.ply"), true, at("s.ply"));
    EXPECT_NE(first, second);
    EXPECT_TRUE(fs::is_regular_file(first));
    EXPECT_EQ(fs::file_size(first), 0u);
    EXPECT_TRUE(fs::is_directory(second));
    for (const fs::path& p : {first, second}) {
        fs::remove(p);
        detail::forget_temporary(p);
    }
    EXPECT_THROW(detail::create_temporary(at("missing/s.ply"), false, at("missing/s.ply")), Error);
    EXPECT_EQ(files(), 0u);
}

} // namespace
} // namespace tetiso
