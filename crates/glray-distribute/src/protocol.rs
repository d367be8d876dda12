//! The messages ranks exchange, each carrying the frame it belongs to (a rank may be a frame
//! ahead of another: its messages wait until that frame), encoded with postcard; big fields
//! shuffled and compressed (`pack`). Pixels travel as their bytes (little-endian floats: every
//! rank of a job is the same kind of machine; the scene encoding checks the byte order of the
//! first message).

use glray_render::paged::BlockRef;
use serde::{Deserialize, Serialize};

use crate::pack::{Compression, Packed};

/// A paged mesh's layout as it travels: its stand-in's id and its blocks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LayoutEntry {
    pub mesh: u64,
    pub blocks: Vec<BlockEntry>,
}

/// A block of a layout (`BlockRef`) as it travels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BlockEntry {
    pub key: u64,
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub triangles: u32,
    pub bytes: u64,
}

impl From<&BlockRef> for BlockEntry {
    fn from(r: &BlockRef) -> BlockEntry {
        BlockEntry { key: r.key, min: r.min.to_array(), max: r.max.to_array(), triangles: r.triangles, bytes: r.bytes }
    }
}

impl BlockEntry {
    pub fn to_ref(&self) -> BlockRef {
        BlockRef {
            key: self.key,
            min: self.min.into(),
            max: self.max.into(),
            triangles: self.triangles,
            bytes: self.bytes,
        }
    }
}

/// What a rank says of its frame to rank 0 when its share is traced.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RankReport {
    pub tiles: u32,
    pub rays: u64,
    /// Seconds spent tracing its tiles.
    pub trace: f64,
}

/// A rectangle of the window, in pixels, rows counted from the bottom (GL's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Rect {
    pub fn area(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// The part of this rectangle in rows `rows`, if any.
    pub fn rows(&self, rows: std::ops::Range<u32>) -> Option<Rect> {
        let (y0, y1) = (self.y.max(rows.start), (self.y + self.height).min(rows.end));
        (y1 > y0 && self.width > 0).then_some(Rect { y: y0, height: y1 - y0, ..*self })
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Message {
    /// A rank's captured frame (`glray_scene::encode`, packed), with what its settings must
    /// agree on, and the part of the window its own data covers (None: nothing drawn): the part
    /// of the picture it is sent back (`Part`).
    Scene { frame: u64, settings: u64, want: Option<Rect>, scene: Packed },
    /// Rank 0's settings changed (from the live control panel): every rank makes the same
    /// changes (setting, value) before it traces this frame, after which their settings agree
    /// on `settings` again. Sent before rank 0's scene of the frame.
    Settings { frame: u64, settings: u64, changes: Vec<(String, String)> },
    /// A render rank asks the master for more tiles.
    Ask { frame: u64 },
    /// The master's answer: tiles to trace, or none (the frame's tiles are all handed out).
    Grant { frame: u64, tiles: Vec<u32> },
    /// Rows `first_row..first_row + rows` of a traced tile, for the rank whose band holds them
    /// (`full`: its depth, colours before rounding or RGBA, and AO) or whose band's denoising
    /// reads them (only their AO, without `lit`).
    Rows {
        frame: u64,
        tile: u32,
        first_row: u32,
        rows: u32,
        full: bool,
        rgba: Packed,
        depth: Packed,
        colors: Packed,
        ao: Packed,
    },
    /// The last frame's denoising history of these rows, asked of the rank whose band held
    /// them.
    HistoryAsk { frame: u64, rows: Vec<(u32, u32)> },
    /// The answer: the rows from `first` (`Past`s), or `held` false when they are not held.
    History { frame: u64, first: u32, rows: u32, held: bool, past: Packed },
    /// A part of the finished picture, for the rank whose data covers it.
    Part { frame: u64, rect: Rect, rgba: Packed, depth: Packed },
    /// A rank's share is traced and every tile of it sent.
    Done { frame: u64, report: RankReport },
    /// A rank has done its part of the frame (sent only where glray's messages move on the
    /// host's thread: every rank waits for every other's before it leaves the frame, so that
    /// each is there to answer the others' asks).
    Finished { frame: u64 },
    /// Paging: the layouts of the sender's meshes new in `frame` (sent before its scene).
    Layouts { frame: u64, layouts: Vec<LayoutEntry> },
    /// Paging: blocks of the receiver's it asks for.
    BlockAsk { frame: u64, keys: Vec<u64> },
    /// Paging: the blocks asked for (None: the sender does not hold it).
    BlockData { frame: u64, blocks: Vec<(u64, Option<Packed>)> },
}

impl Message {
    pub fn frame(&self) -> u64 {
        match self {
            Message::Scene { frame, .. }
            | Message::Settings { frame, .. }
            | Message::Ask { frame }
            | Message::Grant { frame, .. }
            | Message::Rows { frame, .. }
            | Message::HistoryAsk { frame, .. }
            | Message::History { frame, .. }
            | Message::Part { frame, .. }
            | Message::Done { frame, .. }
            | Message::Finished { frame }
            | Message::Layouts { frame, .. }
            | Message::BlockAsk { frame, .. }
            | Message::BlockData { frame, .. } => *frame,
        }
    }

    /// The bytes its packed fields unpack to and travel as (what compression saved).
    pub fn packed_sizes(&self) -> (u64, u64) {
        let fields: Vec<&Packed> = match self {
            Message::Scene { scene, .. } => vec![scene],
            Message::Rows { rgba, depth, colors, ao, .. } => vec![rgba, depth, colors, ao],
            Message::History { past, .. } => vec![past],
            Message::Part { rgba, depth, .. } => vec![rgba, depth],
            Message::BlockData { blocks, .. } => blocks.iter().filter_map(|(_, b)| b.as_ref()).collect(),
            _ => vec![],
        };
        fields.iter().map(|p| p.sizes()).fold((0, 0), |(r, s), (a, b)| (r + a, s + b))
    }

    /// The message's bytes. A scene goes as its own bytes after a short header (`RAW_SCENE`,
    /// frame, settings, the part wanted, how it is packed): at 10M triangles it is 400 MB, and
    /// every copy of it costs.
    pub fn encode(self) -> Vec<u8> {
        if let Message::Scene { frame, settings, want, scene } = self {
            let (how, value_size, raw, mut bytes) = scene.into_parts();
            let mut header = Vec::with_capacity(RAW_HEADER);
            header.push(RAW_SCENE);
            header.extend_from_slice(&frame.to_le_bytes());
            header.extend_from_slice(&settings.to_le_bytes());
            let w = want.unwrap_or(Rect { x: 0, y: 0, width: 0, height: 0 });
            header.push(u8::from(want.is_some()));
            for v in [w.x, w.y, w.width, w.height] {
                header.extend_from_slice(&v.to_le_bytes());
            }
            header.extend_from_slice(&raw.to_le_bytes());
            header.push(how);
            header.extend_from_slice(&value_size.to_le_bytes());
            bytes.splice(0..0, header);
            return bytes;
        }
        // Writing to a Vec cannot fail; every message serializes.
        postcard::to_extend(&self, Vec::with_capacity(64 + self.packed_sizes().1 as usize)).expect("a message encodes")
    }

    pub fn decode(mut bytes: Vec<u8>) -> Result<Message, String> {
        if bytes.first() == Some(&RAW_SCENE) {
            if bytes.len() < RAW_HEADER {
                return Err(format!("a scene message cut short ({} bytes)", bytes.len()));
            }
            let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
            let half = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
            let (frame, settings) = (word(1), word(9));
            let rect = Rect { x: half(18), y: half(22), width: half(26), height: half(30) };
            let want = (bytes[17] != 0).then_some(rect);
            let (raw, how) = (word(34), bytes[42]);
            let value_size = u16::from_le_bytes([bytes[43], bytes[44]]);
            bytes.drain(..RAW_HEADER);
            return Ok(Message::Scene {
                frame,
                settings,
                want,
                scene: Packed::from_parts(how, value_size, raw, bytes),
            });
        }
        postcard::from_bytes(&bytes).map_err(|e| format!("a damaged message ({} bytes): {e}", bytes.len()))
    }
}

/// The first byte of a scene message: never the first byte of a postcard-encoded `Message`
/// (its variant's number, a varint below 128).
const RAW_SCENE: u8 = 0xFF;
/// Marker, frame, settings, the part wanted (a flag and four numbers), the raw size, how it is
/// packed (`Packed`'s kind and value size).
const RAW_HEADER: usize = 1 + 8 + 8 + 1 + 16 + 8 + 1 + 2;

/// The values of a packed field of `size`-byte values (None: damaged, or not whole values).
pub fn unpacked<T: bytemuck::Pod>(p: Packed) -> Option<Vec<T>> {
    let bytes = p.unpack().ok()?;
    (bytes.len() % std::mem::size_of::<T>() == 0).then(|| bytemuck::pod_collect_to_vec(&bytes))
}

/// `values` packed as `how` says, shuffled by `T`'s size (a pixel record as one value).
pub fn packed<T: bytemuck::Pod>(values: &[T], how: Compression) -> Packed {
    Packed::new(bytemuck::cast_slice(values), std::mem::size_of::<T>(), how)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_cross_intact() {
        let how = Compression::Lz4;
        let depth: Vec<f32> = (0..5000).map(|k| 0.5 + k as f32 * 1e-6).collect();
        let rows = Message::Rows {
            frame: 9,
            tile: 3,
            first_row: 64,
            rows: 10,
            full: true,
            rgba: packed(&[7u8; 2000], how),
            depth: packed(&depth, how),
            colors: packed::<f32>(&[], how),
            ao: packed(&[1.5f32; 300], how),
        };
        let (raw, sent) = rows.packed_sizes();
        assert!(raw == 2000 + 20000 + 1200 && sent < raw / 3, "{raw} {sent}");
        let m = Message::decode(rows.clone().encode()).unwrap();
        assert_eq!(m, rows);
        let Message::Rows { depth: d, .. } = m else { panic!() };
        assert_eq!(unpacked::<f32>(d), Some(depth));
        assert!(Message::decode(vec![200, 1]).is_err());
        for want in [None, Some(Rect { x: 1, y: 2, width: 30, height: 40 })] {
            let scene = Message::Scene { frame: 3, settings: 99, want, scene: Packed::new(&[1, 2, 3], 4, how) };
            assert_eq!(Message::decode(scene.clone().encode()), Ok(scene));
        }
        assert!(Message::decode(vec![0xFF, 1, 2]).is_err(), "a scene cut short");
        let r = Rect { x: 0, y: 10, width: 5, height: 20 };
        assert_eq!(r.rows(0..15), Some(Rect { y: 10, height: 5, ..r }));
        assert_eq!(r.rows(30..40), None);
    }
}
