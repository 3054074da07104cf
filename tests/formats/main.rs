//! The animation readers against independent implementations: each module reads files that
//! another tool wrote (usd-core, Blender, the Khronos samples) and compares frames, times and
//! what the file says about its axes with that tool's own evaluation.

mod alembic;
mod fbx;
mod gltf;
mod mdd;
mod usd;
