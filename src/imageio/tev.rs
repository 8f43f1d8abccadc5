//! Live preview in [tev](https://github.com/Tom94/tev) over its TCP protocol, as
//! pbrt-v4's `--display-server` does it.
//!
//! ```text
//! tev &                                                    # listens on 127.0.0.1:14158
//! pbrt-sppm render scene.pbrt --display-server localhost:14158
//! ```
//! Each message is its total length (u32, little-endian, the length field included),
//! a type byte and its fields; strings end with a NUL. The image is created once per
//! connection (type 4: grab focus, name, width, height, channel count, channel names),
//! then sent as 128 × 128 tiles of one channel each (type 3: grab focus, name, channel,
//! x, y, width, height, the floats row by row). A tile is sent again only when it
//! changed. A server that is not there, or goes away, costs one connection attempt a
//! second: the render never waits for it, and a restarted tev gets the image again.

use std::io::Write;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE: u8 = 3;
const TILE: usize = 128;
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// A connection to a tev server that comes and goes.
#[derive(Debug)]
pub struct Tev {
    /// As given (for messages), and resolved when the render was planned.
    address: String,
    resolved: SocketAddr,
    title: String,
    /// Print no warnings; `warned` once a failure was told (one warning a render).
    quiet: bool,
    warned: bool,
    stream: Option<TcpStream>,
    last_attempt: Option<Instant>,
    /// Per tile and channel, a hash of what tev shows (none: nothing sent yet).
    sent: Vec<Option<u64>>,
    last_shown: Option<Instant>,
    /// How long the last show took.
    cost: Duration,
}

impl Tev {
    /// For `address` (`host:port`, the host resolved now); the image is named `title`
    /// in tev. An address without a port, a bad port or a host that does not resolve
    /// is an error, before any work.
    pub fn new(address: &str, title: &str, quiet: bool) -> Result<Tev, String> {
        Ok(Tev {
            address: address.into(),
            resolved: resolve(address)?,
            title: title.into(),
            quiet,
            warned: false,
            stream: None,
            last_attempt: None,
            sent: Vec::new(),
            last_shown: None,
            cost: Duration::ZERO,
        })
    }

    /// One warning a render, the first time tev cannot be reached or is lost; the
    /// render goes on and keeps trying.
    fn warn(&mut self, what: String) {
        if !self.quiet && !self.warned {
            let at = &self.address;
            eprintln!("\n--display-server {at}: warning: {what}; rendering goes on, trying again once a second");
        }
        self.warned = true;
    }

    /// As [`Tev::show`] unless `now` (the last image): at most four times a second, and
    /// never more than 2% of the time (the wait after a show is 50 times its cost), since
    /// the render waits while a show runs.
    pub fn show_now_and_then(&mut self, image: impl FnOnce() -> Vec<[f32; 3]>, size: (usize, usize), now: bool) {
        let wait = Duration::from_millis(250).max(self.cost * 50);
        if now || self.last_shown.is_none_or(|t| t.elapsed() >= wait) {
            let start = Instant::now();
            self.show(&image(), size.0, size.1);
            (self.last_shown, self.cost) = (Some(Instant::now()), start.elapsed());
        }
    }

    /// Shows an image of `width` × `height` RGB pixels (row-major), connecting first
    /// if need be. Returns whether tev has it now; a failure drops the connection.
    pub fn show(&mut self, pixels: &[[f32; 3]], width: usize, height: usize) -> bool {
        if self.stream.is_none() && !self.connect(width, height) {
            return false;
        }
        match self.send_tiles(pixels, width, height) {
            Ok(()) => true,
            Err(e) => {
                self.stream = None;
                self.warn(format!("the connection to tev was lost ({e})"));
                false
            }
        }
    }

    /// Connects (at most once a second) and creates the image there.
    fn connect(&mut self, width: usize, height: usize) -> bool {
        if self.last_attempt.is_some_and(|t| t.elapsed() < Duration::from_secs(1)) {
            return false;
        }
        self.last_attempt = Some(Instant::now());
        let stream = match TcpStream::connect_timeout(&self.resolved, Duration::from_millis(200)) {
            Ok(s) => s,
            Err(e) => {
                self.warn(format!("cannot connect to tev ({e})"));
                return false;
            }
        };
        let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
        let _ = stream.set_nodelay(true);
        self.stream = Some(stream);
        let tiles = width.div_ceil(TILE) * height.div_ceil(TILE);
        self.sent = vec![None; tiles * CHANNELS.len()];
        let mut m = Message::new(CREATE_IMAGE);
        m.u8(1).str(&self.title).i32(width as i32).i32(height as i32).i32(CHANNELS.len() as i32);
        for c in CHANNELS {
            m.str(c);
        }
        let ok = self.write(&m.finish()).is_ok();
        if !ok {
            self.stream = None;
        }
        ok
    }

    fn send_tiles(&mut self, pixels: &[[f32; 3]], width: usize, height: usize) -> std::io::Result<()> {
        let mut index = 0;
        for y0 in (0..height).step_by(TILE) {
            for x0 in (0..width).step_by(TILE) {
                let (w, h) = (TILE.min(width - x0), TILE.min(height - y0));
                for (c, name) in CHANNELS.iter().enumerate() {
                    let values: Vec<f32> =
                        (y0..y0 + h).flat_map(|y| (x0..x0 + w).map(move |x| pixels[y * width + x][c])).collect();
                    let bytes = float_bytes(&values);
                    let hash = xxhash_rust::xxh3::xxh3_64(&bytes);
                    if self.sent[index] != Some(hash) {
                        let mut m = Message::new(UPDATE_IMAGE);
                        m.u8(0).str(&self.title).str(name);
                        m.i32(x0 as i32).i32(y0 as i32).i32(w as i32).i32(h as i32);
                        m.bytes(&bytes);
                        self.write(&m.finish())?;
                        self.sent[index] = Some(hash);
                    }
                    index += 1;
                }
            }
        }
        Ok(())
    }

    fn write(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        match &mut self.stream {
            Some(s) => s.write_all(bytes),
            None => Err(std::io::ErrorKind::NotConnected.into()),
        }
    }
}

/// `HOST:PORT` resolved to its first address; what is wrong with it otherwise.
pub fn resolve(address: &str) -> Result<SocketAddr, String> {
    let expected = "expected HOST:PORT (tev listens on localhost:14158 by default)";
    let Some((host, port)) = address.rsplit_once(':') else {
        return Err(format!("\"{address}\": no port; {expected}"));
    };
    if host.is_empty() {
        return Err(format!("\"{address}\": no host; {expected}"));
    }
    if !matches!(port.parse::<u16>(), Ok(p) if p > 0) {
        return Err(format!("\"{address}\": the port \"{port}\" is not a number from 1 to 65535"));
    }
    match address.to_socket_addrs().map(|mut a| a.next()) {
        Ok(Some(a)) => Ok(a),
        Ok(None) => Err(format!("\"{address}\": the host \"{host}\" has no address")),
        Err(e) => Err(format!("\"{address}\": the host \"{host}\" cannot be found ({e})")),
    }
}

/// Floats as little-endian bytes.
fn float_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// One message being built: its length is filled in by [`Message::finish`].
struct Message(Vec<u8>);

impl Message {
    fn new(kind: u8) -> Message {
        Message(vec![0, 0, 0, 0, kind])
    }

    fn u8(&mut self, v: u8) -> &mut Self {
        self.0.push(v);
        self
    }

    fn i32(&mut self, v: i32) -> &mut Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }

    fn str(&mut self, s: &str) -> &mut Self {
        // A NUL ends the string on the other side: leave any out.
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
        self
    }

    fn bytes(&mut self, b: &[u8]) -> &mut Self {
        self.0.extend_from_slice(b);
        self
    }

    fn finish(&mut self) -> Vec<u8> {
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        std::mem::take(&mut self.0)
    }
}
