//! The strategy knobs as command-line flags, made at run time from `samplers::knobs::KNOBS`, so
//! that a knob is defined once (in `samplers`) and every command that takes strategy flags
//! (`render`, `strategy`) has all of them, with their help and defaults.
use clap::builder::PossibleValuesParser;
use clap::{Arg, ArgAction, ArgMatches, Command};
use samplers::knobs::{KNOBS, Knob, KnobKind};

/// The knob flags given on the command line, `(flag without --, value)`; a switch's value is empty.
#[derive(Clone, Debug, Default)]
pub struct KnobArgs {
    pub given: Vec<(String, String)>,
}

const HEADING: &str = "Strategy knobs (`manylights strategies` lists which strategy takes which)";

fn knob_arg(k: &'static Knob) -> Arg {
    let arg = Arg::new(k.flag).long(k.flag).help_heading(HEADING);
    match k.kind {
        KnobKind::Switch => arg.action(ArgAction::SetTrue).help(k.help),
        KnobKind::Number => arg
            .value_name("X")
            .allow_negative_numbers(true)
            .help(format!("{} [default: {}]", k.help, k.default_value()))
            .value_parser(move |s: &str| k.parse(s).map(|()| s.to_string())),
        KnobKind::Choice(names) => arg
            .value_name("NAME")
            .help(format!("{} [default: {}]", k.help, k.default_value()))
            .value_parser(PossibleValuesParser::new(names())),
    }
}

impl clap::FromArgMatches for KnobArgs {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let given = KNOBS
            .iter()
            .filter_map(|k| match k.kind {
                KnobKind::Switch => m.get_flag(k.flag).then(|| (k.flag.into(), String::new())),
                _ => m
                    .get_one::<String>(k.flag)
                    .map(|v| (k.flag.to_string(), v.clone())),
            })
            .collect();
        Ok(KnobArgs { given })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for KnobArgs {
    fn augment_args(cmd: Command) -> Command {
        KNOBS.iter().fold(cmd, |cmd, k| cmd.arg(knob_arg(k)))
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}
