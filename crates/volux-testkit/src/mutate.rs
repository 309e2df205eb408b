//! Seeded, deterministic mutations of input files for hostile-input tests.
//!
//! A test describes a valid input as a set of [`InputFile`]s (the file Volux is given plus
//! its companions: sidecar, detached data, PLOT3D q file), each with its [`Layout`] so that
//! mutations can aim at the header. [`mutate`] then draws, from a [`TestRng`], either one to
//! three byte-level operations on one of the files or one file-system case ([`FsCase`]), and
//! returns a [`Mutation`]: the new file contents, the file-system case if any, and a one-line
//! description. The same seed always gives the same mutation.
//!
//! Byte-level operations ([`Op`]): bit flips; byte runs set to 0x00, 0xff, 0x7f or 0x80;
//! truncation (at a random point or to zero length); a number of a text header replaced by
//! `-1`, `0`, `2147483647`, `1e308`, `nan`, a 300-digit number and other boundary values; a
//! 2/4/8-byte field of a binary header overwritten with a boundary value (both byte orders);
//! a JSON value replaced by one of the wrong type or a boundary number, or
//! `"compression": "gzip"` added to a sidecar of plain data; gzip/zlib bombs (megabytes of
//! zeros compressed into a few kilobytes, in place of a compressed data section) and gzip
//! streams whose trailer claims 4 GiB; deep XML nesting; control characters and very long
//! strings inserted in text. Files that are gzip streams (`.gz`) are, most of the time,
//! decompressed, mutated inside and compressed again, so that the mutation reaches the parser
//! rather than the CRC check.
//!
//! File-system cases, applied by [`write_case`]: a directory named like the file, a FIFO
//! (made with `mkfifo`; skipped when it is missing), a symbolic link to `/dev/zero`, a
//! symbolic link loop and a dangling link.
use std::fmt;
use std::io::{Read, Write};
use std::path::Path;
use std::process::Command;

use crate::TestRng;

/// Where a file's header is, so that header mutations can aim at it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// A text header of this many bytes (the whole file for text formats), then data.
    Text(usize),
    /// A binary header of this many bytes, then data.
    Binary(usize),
    /// A JSON document (a sidecar).
    Json,
    /// An XML document (VTK XML); its appended data, if any, is part of it.
    Xml,
}

/// A compression codec.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codec {
    /// gzip (RFC 1952).
    Gzip,
    /// zlib (RFC 1950).
    Zlib,
}

/// One file of a valid input: its name in the case folder, its bytes and how they are laid
/// out.
#[derive(Clone, Debug)]
pub struct InputFile {
    /// The file name (no folder).
    pub name: String,
    /// The content.
    pub bytes: Vec<u8>,
    /// The layout of the content (of the decompressed content when [`InputFile::gzip`]).
    pub layout: Layout,
    /// The whole file is a gzip stream (`.gz`).
    pub gzip: bool,
    /// The bytes after the header are a stream of this codec (NRRD gzip, MetaImage zlib).
    pub data_codec: Option<Codec>,
}

impl InputFile {
    /// A file of `layout`, neither gzip nor holding compressed data.
    pub fn new(name: &str, bytes: Vec<u8>, layout: Layout) -> Self {
        Self {
            name: name.to_string(),
            bytes,
            layout,
            gzip: false,
            data_codec: None,
        }
    }

    /// The same file, marked as a gzip stream of content laid out as before.
    pub fn gzipped(mut self) -> Self {
        self.gzip = true;
        self
    }

    /// The same file, marked as holding a `codec` stream after its header.
    pub fn with_data_codec(mut self, codec: Codec) -> Self {
        self.data_codec = Some(codec);
        self
    }

    /// The header length in the (decompressed) content, clamped to the content.
    fn header_len(&self, content: &[u8]) -> usize {
        match self.layout {
            Layout::Text(n) | Layout::Binary(n) => n.min(content.len()),
            Layout::Json | Layout::Xml => content.len(),
        }
    }
}

/// A byte-level mutation of one file, as drawn (with its positions), for the description.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// Bits flipped, by bit index.
    BitFlips(Vec<usize>),
    /// `len` bytes from `at` set to `value`.
    Boundary {
        /// First byte.
        at: usize,
        /// Number of bytes.
        len: usize,
        /// The value written.
        value: u8,
    },
    /// The content cut to `at` bytes (0: empty).
    Truncate(usize),
    /// The text number at `at..at + len` replaced.
    Number {
        /// First byte of the number.
        at: usize,
        /// Its length.
        len: usize,
        /// The replacement.
        with: String,
    },
    /// A binary header field overwritten.
    Field {
        /// First byte of the field.
        at: usize,
        /// The bytes written.
        bytes: Vec<u8>,
    },
    /// A JSON value at `at..at + len` replaced.
    JsonValue {
        /// First byte of the value.
        at: usize,
        /// Its length.
        len: usize,
        /// The replacement.
        with: String,
    },
    /// `"compression": "gzip"` added to a JSON object.
    SidecarGzip,
    /// The data after the header replaced by `zeros` zero bytes compressed with `codec`.
    Bomb {
        /// The codec.
        codec: Codec,
        /// Decompressed size.
        zeros: usize,
    },
    /// The data after the header replaced by `zeros` plain zero bytes (inside a gzip file:
    /// the gzip stream around them makes the bomb).
    Zeros {
        /// How many zero bytes.
        zeros: usize,
    },
    /// A gzip stream's trailer made to claim 4 GiB - 1 bytes.
    HugeIsize,
    /// `depth` nested elements inserted after the root element (closed or not).
    DeepXml {
        /// Nesting depth.
        depth: usize,
        /// Whether the elements are closed.
        closed: bool,
    },
    /// Control characters inserted at `at`.
    Control {
        /// Where.
        at: usize,
        /// The bytes inserted.
        bytes: Vec<u8>,
    },
    /// A run of `len` copies of `byte` inserted at `at`.
    LongString {
        /// Where.
        at: usize,
        /// How many bytes.
        len: usize,
        /// The byte repeated.
        byte: u8,
    },
}

impl fmt::Display for Op {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Op::BitFlips(bits) => write!(f, "bit flips at bits {bits:?}"),
            Op::Boundary { at, len, value } => write!(f, "{len} bytes at {at} set to {value:#04x}"),
            Op::Truncate(at) => write!(f, "truncated to {at} bytes"),
            Op::Number { at, len, with } => {
                write!(f, "number at {at} (len {len}) -> {}", short(with))
            }
            Op::Field { at, bytes } => write!(f, "field at {at} -> {bytes:02x?}"),
            Op::JsonValue { at, len, with } => {
                write!(f, "JSON value at {at} (len {len}) -> {}", short(with))
            }
            Op::SidecarGzip => write!(f, "\"compression\": \"gzip\" added"),
            Op::Bomb { codec, zeros } => write!(f, "{codec:?} bomb of {zeros} zero bytes"),
            Op::Zeros { zeros } => write!(f, "data replaced by {zeros} zero bytes (gzip bomb)"),
            Op::HugeIsize => write!(f, "gzip trailer claims 4 GiB"),
            Op::DeepXml { depth, closed } => {
                write!(f, "XML nested {depth} deep (closed: {closed})")
            }
            Op::Control { at, bytes } => write!(f, "control bytes {bytes:02x?} inserted at {at}"),
            Op::LongString { at, len, byte } => {
                write!(f, "{len} x {:?} inserted at {at}", char::from(*byte))
            }
        }
    }
}

/// `s` with its middle elided when long, for descriptions.
fn short(s: &str) -> String {
    if s.len() <= 24 {
        format!("{s:?}")
    } else {
        format!("{:?}..({} chars)", &s[..12], s.len())
    }
}

/// A file-system case: the file named `victim` is replaced by something that is not a
/// regular file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FsCase {
    /// A directory (holding one small file).
    Directory,
    /// A FIFO nobody writes to.
    Fifo,
    /// A symbolic link to `/dev/zero`.
    DevZero,
    /// A symbolic link to itself.
    SelfLoop,
    /// Two symbolic links to each other.
    PairLoop,
    /// A symbolic link to a missing file.
    Dangling,
}

const FS_CASES: [FsCase; 6] = [
    FsCase::Directory,
    FsCase::Fifo,
    FsCase::DevZero,
    FsCase::SelfLoop,
    FsCase::PairLoop,
    FsCase::Dangling,
];

/// A mutated input, ready for [`write_case`].
#[derive(Clone, Debug)]
pub struct Mutation {
    /// The files to write: name and content.
    pub files: Vec<(String, Vec<u8>)>,
    /// A file-system case and the name of the file it replaces.
    pub fs: Option<(FsCase, String)>,
    /// One line saying what was done.
    pub what: String,
}

/// Draws a mutation of `files` (`files[0]` is the file Volux is given): a file-system case
/// about one time in twenty, otherwise one to three byte-level operations on one file (the
/// first most of the time).
pub fn mutate(files: &[InputFile], rng: &mut TestRng) -> Mutation {
    let victim = pick_victim(files.len(), rng);
    let mut out: Vec<(String, Vec<u8>)> = files
        .iter()
        .map(|f| (f.name.clone(), f.bytes.clone()))
        .collect();
    if rng.below(20) == 0 {
        let case = FS_CASES[rng.below(FS_CASES.len())];
        let name = files[victim].name.clone();
        let what = format!("{name}: file system: {case:?}");
        return Mutation {
            files: out,
            fs: Some((case, name)),
            what,
        };
    }
    let (bytes, what) = mutate_file(&files[victim], rng);
    out[victim].1 = bytes;
    Mutation {
        files: out,
        fs: None,
        what: format!("{}: {what}", files[victim].name),
    }
}

/// The index of the file to mutate: the first two times in three, else any.
fn pick_victim(n: usize, rng: &mut TestRng) -> usize {
    if n == 1 || rng.below(3) != 0 {
        0
    } else {
        rng.below(n)
    }
}

/// Mutates one file with one to three operations; returns the bytes and a description.
pub fn mutate_file(file: &InputFile, rng: &mut TestRng) -> (Vec<u8>, String) {
    let count = match rng.below(10) {
        0..=6 => 1,
        7 | 8 => 2,
        _ => 3,
    };
    let inner = if file.gzip && rng.below(4) != 0 {
        gunzip(&file.bytes)
    } else {
        None
    };
    let (mut content, inside) = match inner {
        Some(c) => (c, true),
        None => (file.bytes.clone(), false),
    };
    let mut ops = Vec::new();
    for _ in 0..count {
        let op = draw_op(file, &content, inside, rng);
        apply(&op, file, &mut content);
        ops.push(op.to_string());
    }
    let what = ops.join("; ");
    if inside {
        (gzip(&content), format!("inside gzip: {what}"))
    } else {
        (content, what)
    }
}

/// The operations that make sense for `file` (content decompressed when `inside`).
fn candidates(file: &InputFile, inside: bool) -> Vec<u8> {
    // 0 bit flips, 1 boundary run, 2 truncate, 3 control, 4 long string: always.
    let mut v = vec![0, 0, 1, 1, 2, 3, 4];
    match file.layout {
        Layout::Text(_) => v.extend([5, 5, 5]),
        Layout::Binary(_) => v.extend([6, 6, 6]),
        Layout::Json => v.extend([5, 5, 7, 7, 7, 8]),
        Layout::Xml => v.extend([5, 5, 5, 9]),
    }
    if file.data_codec.is_some() || (file.gzip && inside) {
        v.push(10);
    }
    if file.gzip && !inside {
        v.push(11);
    }
    v
}

/// Draws one operation for `content`.
fn draw_op(file: &InputFile, content: &[u8], inside: bool, rng: &mut TestRng) -> Op {
    let kinds = candidates(file, inside);
    let header = file.header_len(content);
    match kinds[rng.below(kinds.len())] {
        0 => bit_flips(content.len(), rng),
        1 => boundary_run(content.len(), header, rng),
        2 => truncate(content.len(), rng),
        3 => control(content.len(), header, rng),
        4 => long_string(content.len(), header, rng),
        5 => number(&content[..header], rng).unwrap_or_else(|| truncate(content.len(), rng)),
        6 => field(header, rng),
        7 => json_value(content, rng).unwrap_or(Op::SidecarGzip),
        8 => Op::SidecarGzip,
        9 => Op::DeepXml {
            depth: [1_000, 20_000, 200_000][rng.below(3)],
            closed: rng.below(2) == 0,
        },
        10 => bomb(file, rng),
        _ => Op::HugeIsize,
    }
}

/// A random position in `0..=n`, inside the first `header` bytes three times in four.
fn position(n: usize, header: usize, rng: &mut TestRng) -> usize {
    if header > 0 && rng.below(4) != 0 {
        rng.below(header.min(n) + 1)
    } else {
        rng.below(n + 1)
    }
}

fn bit_flips(n: usize, rng: &mut TestRng) -> Op {
    let count = 1 + rng.below(8);
    Op::BitFlips((0..count).map(|_| rng.below(n.max(1) * 8)).collect())
}

fn boundary_run(n: usize, header: usize, rng: &mut TestRng) -> Op {
    let len = [1, 2, 4, 8, 64, 4096][rng.below(6)];
    Op::Boundary {
        at: position(n, header, rng),
        len,
        value: [0x00, 0xff, 0x7f, 0x80][rng.below(4)],
    }
}

fn truncate(n: usize, rng: &mut TestRng) -> Op {
    if rng.below(5) == 0 {
        Op::Truncate(0)
    } else {
        Op::Truncate(rng.below(n.max(1)))
    }
}

fn control(n: usize, header: usize, rng: &mut TestRng) -> Op {
    const SEQS: [&[u8]; 8] = [
        b"\x1b[31m",
        b"\x1b]0;title\x07",
        b"\x00",
        b"\r",
        b"\x07\x08\x7f",
        "\u{9b}2J".as_bytes(),
        b"\xff\xfe",
        b"\t\x0b\x0c",
    ];
    Op::Control {
        at: position(n, header, rng),
        bytes: SEQS[rng.below(SEQS.len())].to_vec(),
    }
}

fn long_string(n: usize, header: usize, rng: &mut TestRng) -> Op {
    Op::LongString {
        at: position(n, header, rng),
        len: [300, 70_000, 1_000_000][rng.below(3)],
        byte: [b'A', b'9', b' ', b'\n'][rng.below(4)],
    }
}

/// The replacements of a text number.
fn number_values() -> Vec<String> {
    let mut v: Vec<String> = [
        "-1",
        "0",
        "2147483647",
        "2147483648",
        "4294967296",
        "9223372036854775807",
        "18446744073709551616",
        "-2147483648",
        "1e308",
        "-1e308",
        "1e-320",
        "nan",
        "inf",
        "-inf",
        "0.5",
        "-0",
        "65536",
    ]
    .iter()
    .map(ToString::to_string)
    .collect();
    v.push("9".repeat(300));
    v
}

/// The byte ranges of the numbers of `text`: maximal runs of `0-9 . e E + -` holding a digit.
pub fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let is_num = |b: u8| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-');
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if !is_num(text[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < text.len() && is_num(text[i]) {
            i += 1;
        }
        if text[start..i].iter().any(u8::is_ascii_digit) {
            out.push((start, i - start));
        }
    }
    out
}

fn number(header: &[u8], rng: &mut TestRng) -> Option<Op> {
    let nums = numbers(header);
    if nums.is_empty() {
        return None;
    }
    let (at, len) = nums[rng.below(nums.len())];
    let values = number_values();
    Some(Op::Number {
        at,
        len,
        with: values[rng.below(values.len())].clone(),
    })
}

/// A boundary value of `width` bytes (2, 4 or 8), little-endian.
fn boundary_le(width: usize, rng: &mut TestRng) -> Vec<u8> {
    let v: u64 = match rng.below(8) {
        0 => 0,
        1 => u64::MAX,
        2 => (1 << (8 * width - 1)) - 1,
        3 => 1 << (8 * width - 1),
        4 => 1,
        5 => f32::NAN.to_bits() as u64,
        6 => f32::INFINITY.to_bits() as u64,
        _ => 1e38f32.to_bits() as u64,
    };
    v.to_le_bytes()[..width].to_vec()
}

fn field(header: usize, rng: &mut TestRng) -> Op {
    let width = [2, 4, 4, 8][rng.below(4)];
    let slots = (header / 2).max(1);
    let at = 2 * rng.below(slots);
    let mut bytes = boundary_le(width, rng);
    if rng.below(2) == 0 {
        bytes.reverse();
    }
    Op::Field { at, bytes }
}

/// The replacements of a JSON value: wrong types, boundary numbers, odd type names.
fn json_values() -> Vec<String> {
    let mut v: Vec<String> = [
        "\"x\"",
        "null",
        "true",
        "[]",
        "{}",
        "[[[[1]]]]",
        "[1, 2]",
        "[0, 0, 0]",
        "[-1, 2, 2]",
        "[4294967296, 4294967296, 4294967296]",
        "[1e308, 1, 1]",
        "\"gzip\"",
        "\"uint64\"",
        "\"float64\"",
        "\"big\"",
        "\"\u{1b}[2J\"",
        "-1",
        "1e308",
    ]
    .iter()
    .map(ToString::to_string)
    .collect();
    v.push(format!("\"{}\"", "x".repeat(100_000)));
    v.push(format!("{}1{}", "[".repeat(5_000), "]".repeat(5_000)));
    v
}

/// The end of the JSON value starting at `i` (after white space): a balanced bracket
/// group, a string, or a bare token.
fn json_value_end(text: &[u8], i: usize) -> usize {
    let mut depth = 0i32;
    let mut in_str = false;
    let mut j = i;
    while j < text.len() {
        let b = text[j];
        if in_str {
            if b == b'\\' {
                j += 1;
            } else if b == b'"' {
                in_str = false;
                if depth == 0 {
                    return j + 1;
                }
            }
        } else {
            match b {
                b'"' => in_str = true,
                b'[' | b'{' => depth += 1,
                b']' | b'}' if depth == 0 => return j,
                b']' | b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        return j + 1;
                    }
                }
                b',' if depth == 0 => return j,
                _ => {}
            }
        }
        j += 1;
    }
    j
}

fn json_value(text: &[u8], rng: &mut TestRng) -> Option<Op> {
    let colons: Vec<usize> = (0..text.len()).filter(|&i| text[i] == b':').collect();
    if colons.is_empty() {
        return None;
    }
    let mut at = colons[rng.below(colons.len())] + 1;
    while at < text.len() && text[at].is_ascii_whitespace() {
        at += 1;
    }
    let end = json_value_end(text, at);
    let values = json_values();
    Some(Op::JsonValue {
        at,
        len: end - at,
        with: values[rng.below(values.len())].clone(),
    })
}

fn bomb(file: &InputFile, rng: &mut TestRng) -> Op {
    let zeros = [1 << 20, 4 << 20, 8 << 20][rng.below(3)];
    if file.data_codec.is_none() {
        return Op::Zeros { zeros };
    }
    let codec = match (file.data_codec, rng.below(4)) {
        (Some(c), 1..=3) => c,
        (_, 0) => Codec::Zlib,
        _ => Codec::Gzip,
    };
    Op::Bomb { codec, zeros }
}

/// Applies `op` to `content` (decompressed when the file is gzip and `op` reaches inside).
pub fn apply(op: &Op, file: &InputFile, content: &mut Vec<u8>) {
    let n = content.len();
    match op {
        Op::BitFlips(bits) => {
            for &b in bits.iter().filter(|&&b| b / 8 < n) {
                content[b / 8] ^= 1 << (b % 8);
            }
        }
        Op::Boundary { at, len, value } => {
            let end = (at + len).min(n);
            content[(*at).min(n)..end].fill(*value);
        }
        Op::Truncate(at) => content.truncate(*at),
        Op::Number { at, len, with } | Op::JsonValue { at, len, with } => {
            splice(content, *at, *len, with.as_bytes());
        }
        Op::Field { at, bytes } => {
            let end = (at + bytes.len()).min(n);
            let at = (*at).min(end);
            content[at..end].copy_from_slice(&bytes[..end - at]);
        }
        Op::SidecarGzip => add_gzip_key(content),
        Op::Bomb { codec, zeros } => {
            let header = file.header_len(content);
            content.truncate(header);
            content.extend(compress(*codec, &vec![0u8; *zeros]));
        }
        Op::Zeros { zeros } => {
            let header = file.header_len(content);
            content.truncate(header);
            content.resize(header + zeros, 0);
        }
        Op::HugeIsize => {
            let at = n.saturating_sub(4);
            content[at..].fill(0xff);
        }
        Op::DeepXml { depth, closed } => deep_xml(content, *depth, *closed),
        Op::Control { at, bytes } => splice(content, *at, 0, bytes),
        Op::LongString { at, len, byte } => splice(content, *at, 0, &vec![*byte; *len]),
    }
}

/// Replaces `content[at..at + len]` (clamped) by `with`.
fn splice(content: &mut Vec<u8>, at: usize, len: usize, with: &[u8]) {
    let at = at.min(content.len());
    let end = (at + len).min(content.len());
    content.splice(at..end, with.iter().copied());
}

/// Adds `"compression": "gzip",` after the first `{` (or makes the document that object).
fn add_gzip_key(content: &mut Vec<u8>) {
    const KEY: &[u8] = b"\"compression\": \"gzip\", ";
    match content.iter().position(|&b| b == b'{') {
        Some(i) => splice(content, i + 1, 0, KEY),
        None => *content = b"{\"compression\": \"gzip\"}".to_vec(),
    }
}

/// Inserts `depth` nested `<a>` elements after the first element start tag past the XML
/// declaration (the root), closed or not.
fn deep_xml(content: &mut Vec<u8>, depth: usize, closed: bool) {
    let root = content
        .windows(2)
        .position(|w| w[0] == b'<' && w[1] != b'?')
        .unwrap_or(0);
    let at = content[root..]
        .iter()
        .position(|&b| b == b'>')
        .map_or(content.len(), |i| root + i + 1);
    let mut nest = b"<a>".repeat(depth);
    if closed {
        nest.extend(b"</a>".repeat(depth));
    }
    splice(content, at, 0, &nest);
}

/// `bytes` compressed with `codec`.
pub fn compress(codec: Codec, bytes: &[u8]) -> Vec<u8> {
    match codec {
        Codec::Gzip => gzip(bytes),
        Codec::Zlib => zlib(bytes),
    }
}

/// `bytes` as a zlib stream.
pub fn zlib(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).expect("writing to memory");
    e.finish().expect("writing to memory")
}

/// `bytes` as a gzip stream.
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).expect("writing to memory");
    e.finish().expect("writing to memory")
}

/// The content of a gzip stream, or `None` when it is not one (or larger than 64 MiB).
pub fn gunzip(bytes: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .take(64 << 20)
        .read_to_end(&mut out)
        .ok()?;
    Some(out)
}

/// Writes `m` into the folder `dir` and applies its file-system case. Returns `Ok(false)`
/// when the case cannot be made here (no `mkfifo`): the caller skips it.
pub fn write_case(dir: &Path, m: &Mutation) -> std::io::Result<bool> {
    for (name, bytes) in &m.files {
        std::fs::write(dir.join(name), bytes)?;
    }
    match &m.fs {
        Some((case, name)) => apply_fs(dir, *case, name),
        None => Ok(true),
    }
}

/// Replaces `dir/name` by the file-system case.
fn apply_fs(dir: &Path, case: FsCase, name: &str) -> std::io::Result<bool> {
    let path = dir.join(name);
    std::fs::remove_file(&path)?;
    match case {
        FsCase::Directory => {
            std::fs::create_dir(&path)?;
            std::fs::write(path.join("inside.txt"), b"not data")?;
        }
        FsCase::Fifo => {
            let made = Command::new("mkfifo").arg(&path).status();
            if !made.is_ok_and(|s| s.success()) {
                return Ok(false);
            }
        }
        FsCase::DevZero => std::os::unix::fs::symlink("/dev/zero", &path)?,
        FsCase::SelfLoop => std::os::unix::fs::symlink(name, &path)?,
        FsCase::PairLoop => {
            let other = format!("{name}.loop");
            std::os::unix::fs::symlink(&other, &path)?;
            std::os::unix::fs::symlink(name, dir.join(other))?;
        }
        FsCase::Dangling => std::os::unix::fs::symlink("missing.file", &path)?,
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files() -> Vec<InputFile> {
        vec![
            InputFile::new(
                "t.nrrd",
                b"NRRD0004\ntype: uchar\nsizes: 2 2 1\n\n\x01\x02\x03\x04".to_vec(),
                Layout::Text(35),
            ),
            InputFile::new(
                "t.raw.json",
                br#"{"dims_xyz": [2, 2, 1], "dtype": "uint8"}"#.to_vec(),
                Layout::Json,
            ),
        ]
    }

    #[test]
    fn mutations_are_deterministic() {
        for seed in 0..200 {
            let a = mutate(&files(), &mut TestRng::new(seed));
            let b = mutate(&files(), &mut TestRng::new(seed));
            assert_eq!(a.what, b.what);
            assert_eq!(a.files, b.files);
            assert_eq!(a.fs, b.fs);
        }
    }

    #[test]
    fn numbers_and_json_values_are_found() {
        assert_eq!(numbers(b"sizes: 2 10 -1.5e3 x"), [(7, 1), (9, 2), (12, 6)]);
        let t = br#"{"a": [1, [2]], "b": "s,}", "c": 3}"#;
        assert_eq!(json_value_end(t, 6), 14);
        assert_eq!(json_value_end(t, 21), 26);
        assert_eq!(json_value_end(t, 33), 34);
    }

    #[test]
    fn gzip_content_is_mutated_inside() {
        let f = InputFile::new("a.gz", gzip(b"hello 12 world"), Layout::Text(14)).gzipped();
        let inside = (0..100)
            .map(|s| mutate_file(&f, &mut TestRng::new(s)))
            .filter(|(_, what)| what.starts_with("inside gzip"))
            .count();
        assert!(inside > 50, "{inside}");
    }

    #[test]
    fn deep_xml_goes_after_the_root() {
        let mut x = b"<?xml version=\"1.0\"?>\n<VTKFile a=\"1\">\n</VTKFile>".to_vec();
        deep_xml(&mut x, 2, true);
        assert!(x.ends_with(b"<VTKFile a=\"1\"><a><a></a></a>\n</VTKFile>"));
    }
}
