//! Every PGE algorithm as one list of plugins.
//!
//! The `pge` command, the playground (`pge-web`) and any host that wants the whole engine
//! register the same plugins in the same order through [`with_all`], so a script sees the
//! same `pge` table everywhere. Where the engine finds its script library and files stays
//! the host's choice (the builder it passes in).

use pge_engine::EngineBuilder;

// The forest plugin's type, for hosts that configure it (a variant cache, sharing).
pub use pge_forest;

/// `builder` with every PGE plugin, `forest` as the forest plugin (one with a variant cache
/// or sharing, or [`pge_forest::ForestPlugin::default`]).
#[must_use]
pub fn with_all(builder: EngineBuilder, forest: pge_forest::ForestPlugin) -> EngineBuilder {
    builder
        .plugin(pge_lsystem::LSystemPlugin)
        .plugin(pge_turtle::TurtlePlugin)
        .plugin(pge_spacecol::SpaceColonizationPlugin)
        .plugin(pge_growth::GrowthPlugin)
        .plugin(pge_conifer::ConiferPlugin)
        .plugin(pge_tree::TreePlugin)
        .plugin(pge_extruder::ExtruderPlugin)
        .plugin(pge_metaballs::MetaballsPlugin)
        .plugin(pge_canvas::CanvasPlugin)
        .plugin(forest)
        .plugin(pge_lod::LodPlugin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_sees_every_algorithm() {
        let engine = with_all(
            pge_engine::Engine::builder(),
            pge_forest::ForestPlugin::default(),
        )
        .build()
        .expect("engine");
        let source = "local names = {'LSystem', 'SpaceColonization', 'Forest', 'Conifer', 'Metaballs', 'Lines', 'Image'}\n\
                      for _, name in ipairs(names) do assert(pge[name], name) end\n\
                      assert(pge.lod and pge.tree, 'modules')\n\
                      return #names";
        let session = engine
            .session(pge_engine::SessionOptions::default())
            .expect("session");
        let result = session.run_source("check.lua", source);
        assert!(result.is_ok(), "{:?}", result.err());
    }
}
