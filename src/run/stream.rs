//! The reading side of the loader: a named thread that reads the file in large blocks, hashes the
//! bytes as stored (SHA-256, in the same pass), gunzips when the file starts with the gzip magic
//! bytes, and hands over text chunks cut after their last newline.
//!
//! Hashing and decompression thus run beside the parsing of the previous chunk. At most two
//! chunks wait in the channel, so memory stays a few chunk sizes whatever the file size.

use std::io::{self, BufReader, Read};
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};
use std::thread::{Scope, ScopedJoinHandle};

use flate2::read::MultiGzDecoder;
use sha2::{Digest, Sha256};

/// A line longer than this is not a run row: the reader stops with [`Chunk::Overlong`].
pub(super) const MAX_LINE_BYTES: usize = 1 << 20;

/// What the reading thread sends.
pub(super) enum Chunk {
    /// Whole lines of text.
    Text(TextChunk),
    /// The start of a line longer than [`MAX_LINE_BYTES`]; nothing follows.
    Overlong(Vec<u8>),
    /// Reading failed; nothing follows.
    Failed(SourceError),
}

/// Whole lines of text (the final chunk may lack its last newline).
pub(super) struct TextChunk {
    /// The bytes, undecoded (UTF-8 is checked by the parser).
    pub text: Vec<u8>,
    /// Bytes of the file (compressed bytes for gzip) read so far.
    pub raw_done: u64,
    /// On the final chunk: the SHA-256 of all the file's bytes, lower-case hex.
    pub sha256: Option<String>,
}

/// A failure of the reading side.
pub(super) enum SourceError {
    /// The operating system's read failed.
    Io(io::Error),
    /// The gzip stream is corrupt or truncated.
    Gzip(String),
}

/// The bytes as stored: a file, or a slice in memory ([`super::load_bytes`]).
pub(super) type RawSource<'a> = Box<dyn Read + Send + 'a>;

/// Reads a file, hashing and counting every byte that passes.
struct HashingReader<'a> {
    file: RawSource<'a>,
    hasher: Sha256,
    bytes: u64,
    io_failed: bool,
}

impl Read for HashingReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.file.read(buf).inspect_err(|_| self.io_failed = true)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
}

/// The file, decompressed or not.
enum Source<'a> {
    Plain(HashingReader<'a>),
    Gzip(Box<MultiGzDecoder<BufReader<HashingReader<'a>>>>),
}

impl<'a> Source<'a> {
    fn raw(&mut self) -> &mut HashingReader<'a> {
        match self {
            Self::Plain(r) => r,
            Self::Gzip(d) => d.get_mut().get_mut(),
        }
    }

    /// Appends up to `want` bytes to `buf`; `Ok(true)` at the end of the text.
    fn fill(&mut self, buf: &mut Vec<u8>, want: usize) -> Result<bool, SourceError> {
        let want = want as u64;
        let got = match self {
            Self::Plain(r) => r.take(want).read_to_end(buf),
            Self::Gzip(d) => d.take(want).read_to_end(buf),
        };
        match got {
            Ok(n) => Ok((n as u64) < want),
            Err(e) if matches!(self, Self::Gzip(_)) && !self.raw().io_failed => {
                Err(SourceError::Gzip(e.to_string()))
            }
            Err(e) => Err(SourceError::Io(e)),
        }
    }
}

/// Opens the source: gzip when the file starts with `1f 8b`, whatever its name. The bytes read to
/// look are put back in front of the rest, so nothing needs to seek.
fn open(mut file: RawSource<'_>) -> io::Result<Source<'_>> {
    let mut magic = [0u8; 2];
    let mut n = 0;
    while n < magic.len() {
        match file.read(&mut magic[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    let head = io::Cursor::new(magic).take(n as u64);
    let raw = HashingReader {
        file: Box::new(head.chain(file)),
        hasher: Sha256::new(),
        bytes: 0,
        io_failed: false,
    };
    Ok(if n == 2 && magic == [0x1f, 0x8b] {
        Source::Gzip(Box::new(MultiGzDecoder::new(BufReader::with_capacity(
            256 << 10,
            raw,
        ))))
    } else {
        Source::Plain(raw)
    })
}

/// The consuming end of a reading thread.
pub(super) struct Pipe {
    /// The chunks, in file order.
    pub chunks: Receiver<Chunk>,
    /// Used chunk buffers going back to the reader, so that their pages are reused.
    recycle: Sender<Vec<u8>>,
}

impl Pipe {
    /// Hands a chunk's buffer back for reuse.
    pub fn recycle(&self, buffer: Vec<u8>) {
        // The reader may have finished already; the buffer is then simply dropped.
        let _ = self.recycle.send(buffer);
    }
}

/// Starts the named reading thread on `file` within `scope`.
///
/// # Errors
/// When the operating system cannot start a thread.
pub(super) fn spawn<'scope>(
    scope: &'scope Scope<'scope, '_>,
    file: RawSource<'scope>,
    chunk_bytes: usize,
) -> io::Result<(Pipe, ScopedJoinHandle<'scope, ()>)> {
    let (tx, chunks) = sync_channel(1);
    let (recycle, recycled) = channel();
    let handle = std::thread::Builder::new()
        .name("run-reader".to_owned())
        .spawn_scoped(scope, move || produce(file, chunk_bytes, &tx, &recycled))?;
    Ok((Pipe { chunks, recycle }, handle))
}

/// The reading thread's body: sends chunks of about `chunk_bytes` until the end, an error, or the
/// receiver hanging up (cancel).
fn produce(file: RawSource<'_>, chunk_bytes: usize, tx: &SyncSender<Chunk>, recycled: &Receiver<Vec<u8>>) {
    let mut source = match open(file) {
        Ok(source) => source,
        Err(e) => {
            let _ = tx.send(Chunk::Failed(SourceError::Io(e)));
            return;
        }
    };
    let chunk_bytes = chunk_bytes.max(1);
    let mut carry: Vec<u8> = Vec::new();
    loop {
        let mut buf = recycled.try_recv().unwrap_or_default();
        buf.clear();
        buf.reserve(carry.len() + chunk_bytes + 64);
        buf.append(&mut carry);
        let at_end = match source.fill(&mut buf, chunk_bytes) {
            Ok(at_end) => at_end,
            Err(e) => {
                let _ = tx.send(Chunk::Failed(e));
                return;
            }
        };
        if at_end {
            let _ = tx.send(finish(&mut source, buf));
            return;
        }
        match memchr::memrchr(b'\n', &buf) {
            Some(last) => {
                carry.extend_from_slice(&buf[last + 1..]);
                buf.truncate(last + 1);
                let chunk = Chunk::Text(TextChunk {
                    text: buf,
                    raw_done: source.raw().bytes,
                    sha256: None,
                });
                if tx.send(chunk).is_err() {
                    return;
                }
            }
            None if buf.len() > MAX_LINE_BYTES => {
                let _ = tx.send(Chunk::Overlong(buf));
                return;
            }
            None => carry = buf,
        }
    }
}

/// The final chunk: drains what the decompressor left unread so the hash covers the whole file.
fn finish(source: &mut Source, text: Vec<u8>) -> Chunk {
    let raw = source.raw();
    if let Err(e) = io::copy(raw, &mut io::sink()) {
        return Chunk::Failed(SourceError::Io(e));
    }
    let sha256 = format!("{:x}", std::mem::take(&mut raw.hasher).finalize());
    Chunk::Text(TextChunk {
        text,
        raw_done: raw.bytes,
        sha256: Some(sha256),
    })
}
