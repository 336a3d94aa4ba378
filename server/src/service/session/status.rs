//! What `GET /api/sessions/{id}` reports of a session: the contract's
//! `SessionStatus`, filled from the session's state. The renderer's own
//! types (the quality with its typed filter, a device's share without its
//! worker number) become the contract's here, at the edge.

use super::{lock, Session};
use crate::render::scene::{CameraJson, EnvironmentJson, LightInfo, ProjectionJson};
use crate::render::split::DeviceShare;
use crate::render::Quality;
use pathstream_wire as wire;
use std::sync::atomic::Ordering;

/// Status as `GET /api/sessions/{id}` reports it.
pub use pathstream_wire::SessionStatus as Status;

impl Session {
    pub fn status(&self) -> Status {
        let st = lock(&self.state);
        let frame = self.latest();
        let current = frame.generation == st.generation;
        // Only the camera, not the whole scene (this runs for every frame sent).
        let c = st.scene.camera.to_json();
        Status {
            id: self.id.clone(),
            scene: st.scene_name.clone(),
            width: st.width,
            height: st.height,
            camera: camera(c),
            light: st.scene.light_info().map(light),
            environment: Some(environment(st.scene.environment_json())),
            environment_name: (st.scene.environment_map.as_ref()).map(|m| m.map.name.clone()),
            quality: quality(&st.quality),
            state: if st.halted { "halted" } else { "rendering" }.to_owned(),
            spp: if current { frame.spp } else { 0 },
            spp_spread: if current {
                frame.spread
            } else {
                wire::SppSpread::default()
            },
            tiles_done: match (&frame.density, current) {
                (Some(d), true) => d.done_count() as u64,
                _ => 0,
            },
            tiles: crate::render::adaptive::Tiles::new(st.width, st.height).count() as u64,
            tile_size: crate::render::adaptive::TILE_SIZE,
            error_estimate: if current { frame.error_estimate } else { None },
            samples_per_sec: if current { frame.samples_per_sec } else { 0.0 },
            elapsed_ms: st.restarted.elapsed().as_secs_f64() * 1e3,
            rejected: if current { frame.rejected } else { 0 },
            backend: frame.backend.clone(),
            device: frame.device.clone(),
            render_ms: self.render_ns.load(Ordering::Relaxed) as f64 / 1e6,
            devices: (st.devices.iter())
                .map(|(&worker, share)| device_share(worker, share))
                .collect(),
            generation: st.generation,
            failure: st.failure.clone(),
            warnings: st.scene.warnings.clone(),
        }
    }
}

// Each conversion moves every field, as `conversions_lose_nothing` checks.

fn camera(c: CameraJson) -> wire::Camera {
    wire::Camera {
        position: c.position,
        look_at: c.look_at,
        up: c.up,
        vfov_deg: c.vfov_deg,
        near_clip: c.near_clip,
        aperture: c.aperture,
        f_number: c.f_number,
        focus_distance: c.focus_distance,
        projection: match c.projection {
            ProjectionJson::Perspective => wire::Projection::Perspective,
            ProjectionJson::Orthographic => wire::Projection::Orthographic,
            ProjectionJson::Panorama => wire::Projection::Panorama,
        },
        ortho_height: c.ortho_height,
    }
}

fn environment(e: EnvironmentJson) -> wire::Environment {
    match e {
        EnvironmentJson::Color(c) => wire::Environment::Color(c),
        EnvironmentJson::Map(m) => wire::Environment::Map(wire::EnvironmentMap {
            map: m.map,
            sky: m.sky,
            intensity: m.intensity,
            rotation_deg: m.rotation_deg,
            visible: m.visible,
            background: m.background,
        }),
    }
}

fn light(l: LightInfo) -> wire::Light {
    wire::Light {
        index: l.index,
        position: l.position,
        color: l.color,
        intensity: l.intensity,
    }
}

/// The filter by its name; every other field as it is.
fn quality(q: &Quality) -> wire::Quality {
    wire::Quality {
        max_depth: q.max_depth,
        rr_depth: q.rr_depth,
        nee: q.nee,
        filter: q.filter.name().to_owned(),
        sampler: q.sampler.name().to_owned(),
        clamp: q.clamp,
        seed: q.seed,
        adaptive: q.adaptive,
        spp: q.spp,
        time_ms: q.time_ms,
        target_error: q.target_error,
        denoise: q.denoise,
    }
}

/// A device's share, numbered by the worker that renders on it.
fn device_share(worker: usize, share: &DeviceShare) -> wire::DeviceShare {
    wire::DeviceShare {
        worker,
        backend: share.backend.clone(),
        device: share.device.clone(),
        samples: share.samples,
        busy_s: share.busy_s,
        samples_per_sec: share.samples_per_sec,
        failure: share.failure.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;
    use serde_json::{json, Value};

    fn json_of(v: &impl Serialize) -> Value {
        serde_json::to_value(v).expect("serializes")
    }

    /// The renderer's types still serialize themselves (scenes, the CLI):
    /// what the API sends of them must be all of it, so that a field added
    /// there cannot go missing from the contract unnoticed.
    #[test]
    fn conversions_lose_nothing() {
        use crate::render::scene::EnvMapJson;
        let c = CameraJson {
            position: [1.0, 2.0, 3.0],
            look_at: [0.0, 0.5, 0.0],
            up: [0.0, 0.0, 1.0],
            vfov_deg: 33.0,
            near_clip: 0.25,
            aperture: 0.05,
            f_number: Some(2.8),
            focus_distance: Some(4.5),
            projection: ProjectionJson::Orthographic,
            ortho_height: Some(3.0),
        };
        assert_eq!(json_of(&camera(c.clone())), json_of(&c));
        let l = LightInfo {
            index: 3,
            position: [0.0, 9.0, 0.0],
            color: [1.0, 0.5, 0.25],
            intensity: 12.0,
        };
        assert_eq!(json_of(&light(l.clone())), json_of(&l));
        for e in [
            EnvironmentJson::Color([0.1, 0.2, 0.3]),
            EnvironmentJson::Map(EnvMapJson {
                map: "a".repeat(64),
                sky: None,
                intensity: 2.0,
                rotation_deg: 30.0,
                visible: false,
                background: Some([0.5, 0.5, 0.5]),
            }),
            EnvironmentJson::Map(EnvMapJson {
                map: String::new(),
                sky: Some(crate::render::scene::SkyJson {
                    sun_elevation_deg: Some(10.0),
                    sun_azimuth_deg: Some(20.0),
                    sun_direction: Some([1.0, 2.0, 3.0]),
                    time: Some("2026-06-21T12:00:00Z".into()),
                    latitude_deg: Some(1.0),
                    longitude_deg: Some(2.0),
                    sun_size_deg: Some(3.0),
                    sun_intensity: Some(4.0),
                    air: Some(5.0),
                    dust: Some(6.0),
                    ozone: Some(7.0),
                    altitude_m: Some(8.0),
                }),
                intensity: 1.0,
                rotation_deg: 0.0,
                visible: true,
                background: None,
            }),
        ] {
            assert_eq!(json_of(&environment(e.clone())), json_of(&e));
        }
        let q = Quality {
            spp: Some(64),
            target_error: Some(0.01),
            clamp: 0.1,
            adaptive: true,
            ..Quality::default()
        };
        assert_eq!(json_of(&quality(&q)), json_of(&q));
        let mut share = DeviceShare::named("opencl", "gpu");
        share.samples = 1 << 40;
        share.failure = Some("lost".into());
        let mut expected = json_of(&share);
        expected["worker"] = json!(2);
        assert_eq!(json_of(&device_share(2, &share)), expected);
    }
}
