//! `focus ID --x X --y Y`: focus a session's lens on the surface under a
//! pixel of its image, as the page's double-click does.

use crate::{print_status, Failure};
use clap::Args;
use pathstream_client::{CameraPatch, Client};

#[derive(Args, Debug)]
pub struct FocusArgs {
    id: String,
    /// Pixel column, from the image's left (fractions allowed).
    #[arg(long)]
    x: f64,
    /// Pixel row, from the image's top.
    #[arg(long)]
    y: f64,
}

pub async fn focus(client: &Client, a: &FocusArgs) -> Result<(), Failure> {
    let pick = client.pick(&a.id, a.x, a.y).await?;
    let Some(distance) = pick.focus_distance.filter(|_| pick.hit) else {
        let why = match pick.hit {
            false => "the ray through it leaves the scene",
            true => "the surface there is behind the camera's plane",
        };
        return Err(Failure(
            1,
            format!("nothing to focus on at ({}, {}): {why}", a.x, a.y),
        ));
    };
    eprintln!("focus distance {distance}");
    let patch = CameraPatch {
        focus_distance: Some(distance),
        ..CameraPatch::default()
    };
    print_status(&client.set_camera(&a.id, &patch).await?)
}
