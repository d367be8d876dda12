//! The settings the live control panel changes, and how a change is made: checked as any
//! setting is, into new render options, the same on every rank of an MPI job.

use glray_core::config::Config;
use glray_render::Options;

/// The settings the panel changes while the program runs: those that shape the picture and
/// when a frame ends. (Where output goes, threads and MPI are fixed at start.)
pub const CONTROLS: &[&str] = &[
    "preset",
    "ao_samples",
    "ao_distance",
    "ao_intensity",
    "denoise",
    "shadows",
    "reflections",
    "reflectivity",
    "samples",
    "progressive",
    "lighting",
    "trigger",
];

/// `config` with `changes` (setting, value) made, and the render options it gives; or why not
/// (a setting the panel does not change, a bad value, or `preset = off`, which only a restart
/// without glray gives).
pub fn change(config: &Config, changes: &[(String, String)]) -> Result<(Config, Options), String> {
    let changed = config.with_changes(changes, CONTROLS)?;
    let options = Options::from_config(&changed).ok_or_else(|| {
        "preset `off` cannot be set while the program runs (glray would pass every call through from start); \
         allowed here: gl, ao, full"
            .to_string()
    })?;
    Ok((changed, options))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> Config {
        Config::resolve(&[], &[]).unwrap()
    }

    fn set(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn a_change_is_checked_like_any_setting_and_gives_new_options() {
        let (c, o) = change(&config(), &set(&[("preset", "full"), ("ao_samples", "4")])).unwrap();
        assert_eq!(c.value("preset"), Some("full"));
        assert_eq!(o.effects.ao_samples, 4);
        assert!(o.effects.shadows);
        let bad = change(&config(), &set(&[("ao_samples", "many")])).unwrap_err();
        assert!(bad.contains("ao_samples") && bad.contains("allowed"), "{bad}");
        let fixed = change(&config(), &set(&[("threads", "3")])).unwrap_err();
        assert!(fixed.contains("cannot be changed from the panel"), "{fixed}");
        let off = change(&config(), &set(&[("preset", "off")])).unwrap_err();
        assert!(off.contains("off"), "{off}");
        // The settings as a config file read back are the same settings.
        let dir = std::env::temp_dir().join(format!("glray-changes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("settings.toml");
        std::fs::write(&file, c.to_toml(CONTROLS, "test")).unwrap();
        let env = vec![("GLRAY_CONFIG".to_string(), file.display().to_string())];
        let back = Config::resolve(&env, &[]).unwrap();
        assert_eq!(back.picture_settings(), c.picture_settings());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
