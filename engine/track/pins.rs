//! Tracks as a GLB of animated empty nodes, the locators Blender, Maya and three.js import.
//!
//! One node per tracked point, named by its id, with no mesh. One animation, `tracks`, moves
//! each node: a `translation` channel (the point's position) and a `rotation` channel (its
//! orientation frame ([`super::frame`]) as a glTF node carries it: X along the tangent, Y,
//! glTF's up, along the normal, Z along tangent × normal; an importer that turns glTF's +Y up
//! into its own +Z, as Blender's does, turns the node's axes with it, so there the locator's X
//! is the tangent and its Z the normal, as a three-vertex parent's), both `LINEAR`, keyed at every frame's time on the clock
//! ([`super::clock`]). Each node's own translation and rotation are frame 0's, so a viewer that
//! does not play the animation still shows the points where they start. Consecutive keys'
//! quaternions are on one side (non-negative dot product), so LINEAR's slerp turns the short
//! way. glTF is +Y up, in metres: positions are turned by the given [`Orientation`] and
//! written in scene units. The container is [`crate::sequence::glb`]'s.

use super::clock::Clock;
use super::frame::SurfaceFrame;
use super::output::{check_clock, TrackedPoint};
use super::TrackError;
use crate::sequence::glb::{float_accessor, write_container, Accessor, Body};
use crate::sequence::orient::Orientation;
use glam::{DMat3, DQuat, DVec3};
use serde_json::{json, Value};
use std::path::Path;

/// Writes `points` as animated empties on `clock`, turned by `orientation`, atomically.
///
/// Errors: a clock whose frame count is not the trajectories', times that are not strictly
/// increasing once rounded to f32 (glTF's keyframe type), a write failure.
pub fn write_pins_glb(
    path: &Path,
    points: &[TrackedPoint],
    clock: &Clock,
    orientation: Orientation,
) -> Result<(), TrackError> {
    check_clock(points, clock)?;
    let fail = |problem: String| TrackError::Write { path: path.to_owned(), problem };
    let times: Vec<f32> = clock.times.iter().map(|&t| t as f32).collect();
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0] || !w[1].is_finite()) {
        return Err(fail(format!(
            "frame {} at {} s does not follow frame {k} at {} s in 32-bit floats",
            k + 1,
            clock.times[k + 1],
            clock.times[k]
        )));
    }
    let mut body = Body::default();
    let document = document(points, &times, orientation, &mut body);
    let json = serde_json::to_vec(&document).map_err(|e| fail(e.to_string()))?;
    crate::io::write_atomically(path, |w| write_container(w, &json, &body.bytes))
        .map_err(|e| fail(e.to_string()))
}

/// The node rotation of `frame`: X to the tangent, Y to the normal, Z to tangent × normal.
fn node_rotation(frame: &SurfaceFrame) -> DQuat {
    let (n, t) = (DVec3::from(frame.normal), DVec3::from(frame.tangent));
    DQuat::from_mat3(&DMat3::from_cols(t, n, t.cross(n))).normalize()
}

/// Position (turned) and rotation (turned, unit, continuous in sign) of `point` per frame.
fn keys(point: &TrackedPoint, orientation: Orientation) -> (Vec<[f32; 3]>, Vec<[f32; 4]>) {
    let positions = point.trajectory.iter().map(|&p| orientation.apply(p).map(|c| c as f32));
    let mut previous = DQuat::IDENTITY;
    let rotations = (0..point.trajectory.len()).map(|t| {
        let frame = point.surface_frame(t).unwrap_or(SurfaceFrame::WORLD);
        let turned = SurfaceFrame {
            normal: orientation.apply(frame.normal),
            tangent: orientation.apply(frame.tangent),
        };
        let q = node_rotation(&turned);
        let q = if t > 0 && q.dot(previous) < 0.0 { -q } else { q };
        previous = q;
        q.to_array().map(|c| c as f32)
    });
    (positions.collect(), rotations.collect())
}

/// The glTF document of the pins, their keys appended to `body`.
fn document(
    points: &[TrackedPoint],
    times: &[f32],
    orientation: Orientation,
    body: &mut Body,
) -> Value {
    let mut accessors: Vec<Accessor> = Vec::new();
    let mut add = |body: &mut Body, values: &[f32], kind: &str, components: usize| {
        let view = body.view(values.iter().map(|v| v.to_le_bytes()), None);
        let count = values.len() / components;
        accessors.push(float_accessor(Some(view), count, kind, values, components));
        accessors.len() - 1
    };
    let input = (!points.is_empty()).then(|| add(body, times, "SCALAR", 1));
    let (mut nodes, mut channels, mut samplers) = (Vec::new(), Vec::new(), Vec::new());
    for (n, point) in points.iter().enumerate() {
        let (positions, rotations) = keys(point, orientation);
        nodes.push(json!({
            "name": point.id,
            "translation": positions[0],
            "rotation": rotations[0],
        }));
        let translation = add(body, positions.as_flattened(), "VEC3", 3);
        let rotation = add(body, rotations.as_flattened(), "VEC4", 4);
        for (path, output) in [("translation", translation), ("rotation", rotation)] {
            channels
                .push(json!({ "sampler": samplers.len(), "target": { "node": n, "path": path } }));
            samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
        }
    }
    let mut document = json!({
        "asset": { "version": "2.0", "generator": format!("tagsplat {}", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [if points.is_empty() { json!({}) } else { json!({ "nodes": (0..points.len()).collect::<Vec<_>>() }) }],
    });
    if !points.is_empty() {
        document["nodes"] = json!(nodes);
        document["accessors"] = json!(accessors);
        document["bufferViews"] = json!(std::mem::take(&mut body.views));
        document["buffers"] = json!([{ "byteLength": body.bytes.len() }]);
        document["animations"] =
            json!([{ "name": "tracks", "channels": channels, "samplers": samplers }]);
    }
    document
}
