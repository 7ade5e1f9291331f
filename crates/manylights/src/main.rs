//! `manylights`: render, inspect and list scenes and strategies.
mod render_cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "manylights",
    version,
    about = "Many-light direct-illumination research renderer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with a light-sampling strategy to a linear EXR (+ JSON metadata).
    Render(render_cmd::RenderArgs),
    /// Print a scene's triangles, lights by kind, total power and bounds.
    Info {
        /// A glTF file (.gltf/.glb) or `builtin:NAME?key=value&...`.
        scene: String,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// List the built-in scenes and their keys.
    Scenes,
    /// List the strategies.
    Strategies,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(args),
        Command::Info { scene, json } => info(&scene, json),
        Command::Scenes => {
            list_scenes();
            Ok(())
        }
        Command::Strategies => {
            for s in samplers::strategies() {
                println!(
                    "{:<18} {}{}",
                    s.name,
                    s.description,
                    if s.implemented {
                        ""
                    } else {
                        " [not implemented yet]"
                    }
                );
            }
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn list_scenes() {
    for b in render_core::builtin::list_builtins() {
        println!("builtin:{}\n    {}", b.name, b.description);
        for (key, default, help) in &b.keys {
            println!("    {key:<10} default {default:<10} {help}");
        }
    }
}

fn info(spec: &str, json: bool) -> anyhow::Result<()> {
    let scene = render_core::load_scene(spec, None)?;
    let s = &scene.stats;
    if json {
        let v = serde_json::json!({ "scene": spec, "stats": s, "bounds": [scene.bounds.0.to_array(), scene.bounds.1.to_array()], "cameras": scene.cameras.iter().map(|c| &c.name).collect::<Vec<_>>() });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!("scene          {spec}");
    println!(
        "triangles      {} ({} degenerate skipped)",
        s.triangles, s.degenerate_triangles_skipped
    );
    println!(
        "lights         {} triangle, {} sphere, {} point, {} spot, {} directional",
        s.triangle_lights, s.sphere_lights, s.point_lights, s.spot_lights, s.distant_lights
    );
    if s.black_emissive_triangles > 0 {
        println!(
            "               ({} emissive triangles average to black: not lights)",
            s.black_emissive_triangles
        );
    }
    println!("total power    {:.6e} W (bounded lights)", s.total_power_w);
    println!(
        "bounds         {:?} .. {:?}",
        scene.bounds.0.to_array(),
        scene.bounds.1.to_array()
    );
    println!(
        "cameras        {}",
        if scene.cameras.is_empty() {
            "none (a default camera frames the bounds)".to_string()
        } else {
            scene
                .cameras
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    Ok(())
}
