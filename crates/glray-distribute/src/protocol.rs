//! The messages ranks exchange, each carrying the frame it belongs to (a rank may be a frame
//! ahead of another: its messages wait until that frame), encoded with postcard; byte fields as
//! one run of bytes (serde_bytes), not as a sequence of numbers. Pixels travel as their bytes (little-endian floats: every rank of a job is the same kind of machine; the
//! scene encoding checks the byte order of the first message).

use glray_render::denoise::AoPixel;
use serde::{Deserialize, Serialize};

/// What a rank says of its frame to rank 0 when its share is traced.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RankReport {
    pub tiles: u32,
    pub rays: u64,
    /// Seconds spent tracing its tiles.
    pub trace: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Message {
    /// A rank's captured frame (`glray_scene::encode`), with what its settings must agree on.
    Scene {
        frame: u64,
        settings: u64,
        #[serde(with = "serde_bytes")]
        scene: Vec<u8>,
    },
    /// Rank 0's settings changed (from the live control panel): every rank makes the same
    /// changes (setting, value) before it traces this frame, after which their settings agree
    /// on `settings` again. Sent before rank 0's scene of the frame.
    Settings { frame: u64, settings: u64, changes: Vec<(String, String)> },
    /// A render rank asks the master for more tiles.
    Ask { frame: u64 },
    /// The master's answer: tiles to trace, or none (the frame's tiles are all handed out).
    Grant { frame: u64, tiles: Vec<u32> },
    /// A traced tile for the display rank: RGBA bytes, and as bytes its depths, linear colours
    /// and the AO kept apart for denoising (`AoPixel`s; empty when not denoised).
    Tile {
        frame: u64,
        tile: u32,
        #[serde(with = "serde_bytes")]
        rgba: Vec<u8>,
        #[serde(with = "serde_bytes")]
        depth: Vec<u8>,
        #[serde(with = "serde_bytes")]
        colors: Vec<u8>,
        #[serde(with = "serde_bytes")]
        ao: Vec<u8>,
    },
    /// A rank's share is traced and every tile of it sent.
    Done { frame: u64, report: RankReport },
    /// The display rank's finished picture, for every other rank's framebuffer: a sort-last
    /// compositor (IceT) takes each rank's pixels only where that rank's own data projects, so
    /// every rank must hold the whole picture for the composite to be whole.
    Picture {
        frame: u64,
        width: u32,
        height: u32,
        #[serde(with = "serde_bytes")]
        rgba: Vec<u8>,
        #[serde(with = "serde_bytes")]
        depth: Vec<u8>,
    },
}

impl Message {
    pub fn frame(&self) -> u64 {
        match self {
            Message::Scene { frame, .. }
            | Message::Settings { frame, .. }
            | Message::Ask { frame }
            | Message::Grant { frame, .. }
            | Message::Tile { frame, .. }
            | Message::Done { frame, .. }
            | Message::Picture { frame, .. } => *frame,
        }
    }

    /// The message's bytes. A scene goes as its own bytes after a short header (`RAW_SCENE`,
    /// frame, settings): at 10M triangles it is 400 MB, and every copy of it costs.
    pub fn encode(self) -> Vec<u8> {
        if let Message::Scene { frame, settings, mut scene } = self {
            let mut header = Vec::with_capacity(RAW_HEADER);
            header.push(RAW_SCENE);
            header.extend_from_slice(&frame.to_le_bytes());
            header.extend_from_slice(&settings.to_le_bytes());
            scene.splice(0..0, header);
            return scene;
        }
        let room = 64
            + match &self {
                Message::Tile { rgba, depth, colors, ao, .. } => rgba.len() + depth.len() + colors.len() + ao.len(),
                Message::Picture { rgba, depth, .. } => rgba.len() + depth.len(),
                Message::Grant { tiles, .. } => 5 * tiles.len(),
                _ => 0,
            };
        // Writing to a Vec cannot fail; every message serializes.
        postcard::to_extend(&self, Vec::with_capacity(room)).expect("a message encodes")
    }

    pub fn decode(mut bytes: Vec<u8>) -> Result<Message, String> {
        if bytes.first() == Some(&RAW_SCENE) {
            if bytes.len() < RAW_HEADER {
                return Err(format!("a scene message cut short ({} bytes)", bytes.len()));
            }
            let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"));
            let (frame, settings) = (word(1), word(9));
            bytes.drain(..RAW_HEADER);
            return Ok(Message::Scene { frame, settings, scene: bytes });
        }
        postcard::from_bytes(&bytes).map_err(|e| format!("a damaged message ({} bytes): {e}", bytes.len()))
    }
}

/// The first byte of a scene message: never the first byte of a postcard-encoded `Message`
/// (its variant's number, a varint below 128).
const RAW_SCENE: u8 = 0xFF;
const RAW_HEADER: usize = 1 + 8 + 8;

/// A tile's pixels as a message.
pub fn tile_message(frame: u64, t: &glray_render::tiles::TilePixels) -> Message {
    Message::Tile {
        frame,
        tile: t.tile,
        rgba: t.rgba.clone(),
        depth: bytemuck::cast_slice(&t.depth).to_vec(),
        colors: bytemuck::cast_slice(&t.colors).to_vec(),
        ao: bytemuck::cast_slice(&t.ao).to_vec(),
    }
}

/// A picture as a message.
pub fn picture_message(frame: u64, r: &glray_render::Rendered) -> Message {
    Message::Picture {
        frame,
        width: r.width,
        height: r.height,
        rgba: r.rgba.clone(),
        depth: r.depth.iter().flat_map(|d| d.to_le_bytes()).collect(),
    }
}

/// A picture from a message's fields (None when the sizes do not agree).
pub fn picture(width: u32, height: u32, rgba: Vec<u8>, depth: &[u8]) -> Option<glray_render::Rendered> {
    let n = width as usize * height as usize;
    if rgba.len() != 4 * n || depth.len() != 4 * n {
        return None;
    }
    let depth = depth.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    Some(glray_render::Rendered { width, height, rgba, depth })
}

/// A tile's pixels from a message's fields (None when the byte counts are not whole values).
pub fn tile_pixels(
    tile: u32,
    rgba: Vec<u8>,
    depth: &[u8],
    colors: &[u8],
    ao: &[u8],
) -> Option<glray_render::tiles::TilePixels> {
    let ao_size = std::mem::size_of::<AoPixel>();
    if depth.len() % 4 != 0 || colors.len() % 16 != 0 || ao.len() % ao_size != 0 {
        return None;
    }
    let floats =
        |b: &[u8]| -> Vec<f32> { b.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect() };
    let depth = floats(depth);
    let colors = floats(colors).chunks_exact(4).map(glam::Vec4::from_slice).collect();
    // Copied out (the bytes need not sit at a float's alignment).
    let ao = bytemuck::pod_collect_to_vec(ao);
    Some(glray_render::tiles::TilePixels { tile, rgba, depth, colors, ao })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_and_tiles_cross_intact() {
        let t = glray_render::tiles::TilePixels {
            tile: 3,
            rgba: vec![1, 2, 3, 4, 5, 6, 7, 8],
            depth: vec![0.25, 1.0],
            colors: vec![glam::Vec4::new(0.1, 0.2, 0.3, 1.0), glam::Vec4::ONE],
            ao: vec![
                AoPixel { eye: glam::Vec3::new(1.0, 2.0, -3.0), object: 7, hidden: 0.25, ..AoPixel::NONE },
                AoPixel { normal: glam::Vec3::Z, lit: glam::Vec3::ONE, hidden: 1.0, ..AoPixel::NONE },
            ],
        };
        let m = Message::decode(tile_message(9, &t).encode()).unwrap();
        assert_eq!(m.frame(), 9);
        let Message::Tile { tile, rgba, depth, colors, ao, .. } = m else { panic!("{m:?}") };
        assert_eq!(tile_pixels(tile, rgba.clone(), &depth, &colors, &ao), Some(t));
        assert_eq!(tile_pixels(tile, rgba, &depth, &colors, &ao[1..]), None, "AO cut short");
        assert!(Message::decode(vec![200, 1]).is_err());
        let scene = Message::Scene { frame: 3, settings: 99, scene: vec![1, 2, 3] };
        assert_eq!(Message::decode(scene.clone().encode()), Ok(scene));
        assert!(Message::decode(vec![0xFF, 1, 2]).is_err(), "a scene cut short");
        let r = glray_render::Rendered { width: 2, height: 1, rgba: vec![9; 8], depth: vec![0.5, 1.0] };
        let Message::Picture { width, height, rgba, depth, .. } =
            Message::decode(picture_message(4, &r).encode()).unwrap()
        else {
            panic!("not a picture")
        };
        assert_eq!(picture(width, height, rgba, &depth), Some(r));
        assert_eq!(picture(3, 1, vec![0; 8], &[0; 8]), None, "sizes that do not agree");
    }
}
