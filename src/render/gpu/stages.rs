//! Each stage records its own dispatches; the copies between them (the maps' refreshes, the
//! indirect dispatches' arguments) are [`super::frame`]'s, which orders the stages of a
//! submission's frames.

use super::layout::{
    dispatch_args_at, groups, DEEP_DISPATCH, DISPATCH_ARGS_BYTES, LIST_WORKGROUP,
    PROBES_BYTES_PER_PIXEL, SELECT_DISPATCH, SHALLOW_DISPATCH, TOUCHED_ARGS_BYTES,
};
use super::pipelines::{
    CameraPipelines, ContactPipelines, ElastomerPipelines, LedsPipelines, StartPipelines,
    TouchedPipelines,
};
use super::record::{Groups, Recorder};
use super::resources::Resources;
use crate::error::Result;
use crate::render::touched::tile_grid;
use crate::render::Rect;

/// A stage's dispatch over frames of a wave: the bind group whose frame uniforms are
/// theirs (each workgroup finds its own: `use_frame_of`, or the third coordinate for the
/// passes over whole frames), and the workgroups.
#[derive(Clone, Copy)]
pub(super) struct Batch<'a> {
    pub bind: &'a wgpu::BindGroup,
    pub groups: Groups,
}

impl StartPipelines {
    /// The frames' start: their image buffers from the reference, their counters cleared
    /// (the heightfield's clears are [`super::frame`]'s).
    pub fn dispatch<'a>(&'a self, rec: &mut Recorder<'a>, b: Batch<'a>) {
        rec.dispatch(&self.frame_start, b.bind, b.groups);
    }
}

impl ContactPipelines {
    /// Stage 1, contacts' passes over their pressed rects, with their objects' pipeline of
    /// kind `kind` (each pass keeps the deepest press of a texel, so a frame's contacts, in
    /// a pass each, press the skin together); each writes its own penetration into its
    /// field, and the penetration map is refreshed after the last.
    pub fn dispatch<'a>(&'a self, rec: &mut Recorder<'a>, kind: u32, b: Batch<'a>) -> Result<()> {
        rec.dispatch(self.of(kind)?, b.bind, b.groups);
        Ok(())
    }
}

impl ElastomerPipelines {
    /// Stage 2's blends along meridians over the frames' meridian pieces, into the pending
    /// pass; the elastomer map's refresh follows.
    pub fn dispatch_meridians<'a>(&'a self, rec: &mut Recorder<'a>, meridians: &[Batch<'a>]) {
        for b in meridians {
            rec.dispatch(&self.meridians, b.bind, b.groups);
        }
    }

    /// Then along parallels over their texel pieces; the height map's refresh follows.
    pub fn dispatch_parallels<'a>(&'a self, rec: &mut Recorder<'a>, texels: &[Batch<'a>]) {
        for b in texels {
            rec.dispatch(&self.parallels, b.bind, b.groups);
        }
    }

    /// The skin's normals over the texel pieces, into the pending pass: the elastomer
    /// map's refresh follows once the selection's first pass has joined it (both read the
    /// height map alone).
    pub fn record_normals<'a>(&'a self, rec: &mut Recorder<'a>, texels: &[Batch<'a>]) {
        for b in texels {
            rec.dispatch(&self.skin_normals, b.bind, b.groups);
        }
    }
}

impl TouchedPipelines {
    /// Once, after the reference frame's camera pass: the rays' probes into their map, and
    /// per tile of pixels the texels those probes read.
    pub fn record_probe_tiles<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        res: &Resources,
        bind: &'a wgpu::BindGroup,
        (width, height): (u32, u32),
    ) {
        copy_probes_to_map(rec.encoder(), res, (width, height));
        let (tx, ty) = tile_grid(width, height);
        let g = Groups::Direct(groups(tx * ty, LIST_WORKGROUP), 1, 1);
        rec.dispatch(&self.probe_tiles, bind, g);
    }

    /// The frames' tile lists: the tiles of each one's pixel rect whose probes see a
    /// displaced texel, into the pending pass; then where each frame's share of the pass
    /// over them starts, and that pass's size.
    pub fn record_tiles<'a>(&'a self, rec: &mut Recorder<'a>, b: Batch<'a>) {
        rec.dispatch(&self.select_tiles, b.bind, b.groups);
        rec.dispatch(&self.tile_bases, b.bind, Groups::Direct(1, 1, 1));
    }

    /// Once the touched lists are whole: where each frame's share of the camera's passes
    /// over them starts, and those passes' sizes.
    pub fn record_touched_bases<'a>(&'a self, rec: &mut Recorder<'a>, bind: &'a wgpu::BindGroup) {
        rec.dispatch(&self.touched_bases, bind, Groups::Direct(1, 1, 1));
    }

    /// The touched lists of the frames of the wave whose first frame is in `slot`, from the
    /// listed tiles: a pass over all the wave's tile lists, each frame's workgroups after
    /// the one before's, whose arguments [`copy_dispatch_args`] copied.
    pub fn dispatch_listed<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        slot: u64,
        bind: &'a wgpu::BindGroup,
    ) {
        let args = slot * DISPATCH_ARGS_BYTES + dispatch_args_at(SELECT_DISPATCH);
        rec.dispatch(&self.select_listed, bind, Groups::Indirect(args));
    }
}

/// The touched list's dispatch, from the tile list's length: its counter, and one
/// dispatch's arguments.
pub(super) const TILE_LIST_ARGS: (u32, u64) = (SELECT_DISPATCH, 12);
/// The camera's two dispatches, from the touched list's lengths.
pub(super) const TOUCHED_LIST_ARGS: (u32, u64) = (SHALLOW_DISPATCH, TOUCHED_ARGS_BYTES);

/// Indirect dispatch arguments from frame `slot`'s counters (a wave's first frame's hold
/// the wave's), `bytes` of them from counter `first` on ([`TILE_LIST_ARGS`],
/// [`TOUCHED_LIST_ARGS`]), into the frame's dispatch arguments at their place.
pub(super) fn copy_dispatch_args(
    encoder: &mut wgpu::CommandEncoder,
    res: &Resources,
    slot: u64,
    (first, bytes): (u32, u64),
) {
    encoder.copy_buffer_to_buffer(
        &res.counters,
        slot * res.counter_bytes + first as u64 * 4,
        &res.dispatch_args,
        slot * DISPATCH_ARGS_BYTES + dispatch_args_at(first),
        Some(bytes),
    );
}

impl CameraPipelines {
    /// The reference frame: every pixel of `bind`'s pixel rect cast and shaded.
    pub fn record_reference<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        bind: &'a wgpu::BindGroup,
        pixels: Rect,
    ) {
        rec.dispatch(&self.reference, bind, Groups::over(pixels));
    }

    /// Stage 3 of contact frames: the passes over the touched lists of the wave whose first
    /// frame is in `slot`, the shallow pixels' and the deep ones', each over all the wave's
    /// lists of its kind side by side ([`copy_dispatch_args`]).
    pub fn dispatch_touched<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        slot: u64,
        bind: &'a wgpu::BindGroup,
    ) {
        let args = slot * DISPATCH_ARGS_BYTES;
        let (shallow, deep) = (
            args + dispatch_args_at(SHALLOW_DISPATCH),
            args + dispatch_args_at(DEEP_DISPATCH),
        );
        rec.dispatch(&self.shallow, bind, Groups::Indirect(shallow));
        rec.dispatch(&self.deep, bind, Groups::Indirect(deep));
    }
}

impl LedsPipelines {
    /// Stage 4: the sensor's noise over every pixel of the finished frames.
    pub fn record_noise<'a>(&'a self, rec: &mut Recorder<'a>, b: Batch<'a>) {
        rec.dispatch(&self.add_noise, b.bind, b.groups);
    }
}

/// Copies the rays' probes into their map: in one copy when a row of them is a whole
/// number of 256-byte copy rows, else row by row (once per renderer).
fn copy_probes_to_map(encoder: &mut wgpu::CommandEncoder, res: &Resources, (w, h): (u32, u32)) {
    let row_bytes = w * PROBES_BYTES_PER_PIXEL as u32;
    let (rows_per_copy, copies) = if row_bytes.is_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) {
        (h, 1)
    } else {
        (1, h)
    };
    for k in 0..copies {
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: &res.probes,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: k as u64 * row_bytes as u64,
                    bytes_per_row: Some(row_bytes).filter(|_| rows_per_copy > 1),
                    rows_per_image: None,
                },
            },
            wgpu::TexelCopyTextureInfo {
                texture: &res.probe_map.texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y: k, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d {
                width: 2 * w,
                height: rows_per_copy,
                depth_or_array_layers: 1,
            },
        );
    }
}
