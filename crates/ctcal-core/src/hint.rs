//! Options that fix a problem, named in the library's own words.
//!
//! The library never names a command-line flag. A message whose fix is to set an option
//! carries a [`Hint`] for it inside a [`Text`]: the text's `Display` words the option
//! neutrally ("give the sensor size WxH"), which is what the library's callers and the
//! Python package show, and [`Text::render`] lets the `ctcal` binary name its flag instead
//! ("pass FLAG").

use crate::events::Sensor;
use crate::format::Format;
use crate::selection::Roi;
use std::fmt;

/// An option the user sets to fix a problem, with the value to give where it is known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Hint {
    /// The sensor size: the camera's real one (`None`: WxH, to be filled in) or this one.
    Sensor(Option<Sensor>),
    /// Permission to replace ctcal's own files, to write inside an input folder, or to run
    /// work beyond a budget.
    Force,
    /// Sorting the events by time as they are read.
    Sort,
    /// The format to read the input as (`None`: one still to choose).
    Format(Option<Format>),
    /// The start and end of the time window, seconds from the first event.
    TimeWindow,
    /// The events topic of a ROS bag.
    Topic,
    /// The image topic of a ROS bag.
    ImageTopic,
    /// The camera of an MVSEC stereo pair (`left` or `right`).
    Side(String),
    /// The format to write.
    WriteAs(Format),
    /// The display's refresh rate.
    RefreshHz,
    /// The folder of the calibration stimulus that was played.
    Stimulus,
    /// A region of interest.
    Roi(Roi),
    /// Another analysis that answers where this one cannot.
    Analysis(Analysis),
    /// The events and pixels a measurement may afford before it is cut to a region of the
    /// sensor (0: no limit).
    Budget,
}

/// The analyses a fix can point to (the binary names their commands).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Analysis {
    /// The threshold estimate from events alone (events per pixel per second).
    Eppps,
    /// The fit of the pixel model with its noise.
    Fit,
    /// The event statistics.
    Stats,
}

impl Analysis {
    /// The analysis as a noun.
    pub fn name(self) -> &'static str {
        match self {
            Analysis::Eppps => "the events-only estimate (eppps), which needs no frames",
            Analysis::Fit => "the fit",
            Analysis::Stats => "the statistics",
        }
    }
}

impl Hint {
    /// The option as a noun ("the sensor size 346x260").
    pub fn name(&self) -> String {
        match self {
            Hint::Sensor(None) => "the sensor size WxH".into(),
            Hint::Sensor(Some(s)) => format!("the sensor size {s}"),
            Hint::Force => "force".into(),
            Hint::Sort => "sorting by time".into(),
            Hint::Format(None) => "the format".into(),
            Hint::Format(Some(f)) => format!("the format {f}"),
            Hint::TimeWindow => "the window's start and end".into(),
            Hint::Topic => "the events topic".into(),
            Hint::ImageTopic => "the image topic".into(),
            Hint::Side(side) => format!("the {side} camera"),
            Hint::WriteAs(f) => format!("the output format {f}"),
            Hint::RefreshHz => "the display's refresh rate (Hz)".into(),
            Hint::Stimulus => "the stimulus folder".into(),
            Hint::Roi(roi) => format!("the region {roi}"),
            Hint::Analysis(analysis) => analysis.name().into(),
            Hint::Budget => "a larger budget of events and pixels (0: no limit)".into(),
        }
    }

    /// The instruction to set the option ("give the sensor size 346x260").
    pub fn act(&self) -> String {
        match self {
            Hint::Force => "force it".into(),
            Hint::Sort => "sort the events by time".into(),
            Hint::Side(side) => format!("read the {side} camera"),
            Hint::WriteAs(f) => format!("write {f}"),
            other => format!("give {}", other.name()),
        }
    }
}

/// How a text mentions an option.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Part {
    Words(String),
    /// An instruction to set it: "give the sensor size WxH" / "pass FLAG".
    Act(Hint),
    /// The option itself: "the format evt2" / "FLAG".
    Name(Hint),
    /// An aside naming the option that does what the words say: nothing / " (FLAG)".
    Aside(Hint),
}

/// Words that may mention options: shown neutrally by `Display`, with flags by
/// [`Text::render`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Text {
    parts: Vec<Part>,
}

impl Text {
    pub fn words(mut self, words: impl Into<String>) -> Self {
        self.parts.push(Part::Words(words.into()));
        self
    }

    /// Appends the instruction to set `hint`'s option.
    pub fn act(mut self, hint: Hint) -> Self {
        self.parts.push(Part::Act(hint));
        self
    }

    /// Appends the option itself, as a noun.
    pub fn name(mut self, hint: Hint) -> Self {
        self.parts.push(Part::Name(hint));
        self
    }

    /// Appends an aside naming the option that does what the words before it say (shown
    /// only where options have names of their own, such as flags).
    pub fn aside(mut self, hint: Hint) -> Self {
        self.parts.push(Part::Aside(hint));
        self
    }

    /// Appends `other`.
    pub fn and(mut self, other: &Text) -> Self {
        self.parts.extend(other.parts.iter().cloned());
        self
    }

    /// This text as a problem, then its fix on the next line (`"...\n  fix: ..."`).
    pub fn fixed_by(self, fix: &Text) -> Self {
        self.words("\n  fix: ").and(fix)
    }

    /// The options the text mentions.
    pub fn hints(&self) -> impl Iterator<Item = &Hint> {
        self.parts.iter().filter_map(|part| match part {
            Part::Words(_) => None,
            Part::Act(h) | Part::Name(h) | Part::Aside(h) => Some(h),
        })
    }

    /// The text with each option named by `flag` (a flag and its value): an instruction
    /// becomes "pass FLAG", an aside " (FLAG)".
    pub fn render(&self, flag: &dyn Fn(&Hint) -> String) -> String {
        self.parts
            .iter()
            .map(|part| match part {
                Part::Words(w) => w.clone(),
                Part::Act(h) => format!("pass {}", flag(h)),
                Part::Name(h) => flag(h),
                Part::Aside(h) => format!(" ({})", flag(h)),
            })
            .collect()
    }
}

impl fmt::Display for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for part in &self.parts {
            match part {
                Part::Words(w) => f.write_str(w)?,
                Part::Act(h) => f.write_str(&h.act())?,
                Part::Name(h) => f.write_str(&h.name())?,
                Part::Aside(_) => {}
            }
        }
        Ok(())
    }
}

impl From<String> for Text {
    fn from(words: String) -> Self {
        Text::default().words(words)
    }
}

impl From<&str> for Text {
    fn from(words: &str) -> Self {
        Text::default().words(words)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flag(hint: &Hint) -> String {
        match hint {
            Hint::Sensor(Some(s)) => format!("-s {s}"),
            _ => "-x".into(),
        }
    }

    #[test]
    fn a_text_words_its_options_neutrally_or_as_the_caller_names_them() {
        let text = Text::from("if the header is damaged, ")
            .act(Hint::Sensor(Some(Sensor::new(346, 260))))
            .words("; or sort the events first")
            .aside(Hint::Sort);
        assert_eq!(
            text.to_string(),
            "if the header is damaged, give the sensor size 346x260; or sort the events first"
        );
        assert_eq!(
            text.render(&flag),
            "if the header is damaged, pass -s 346x260; or sort the events first (-x)"
        );
        assert_eq!(text.hints().count(), 2);
        let named = Text::default()
            .name(Hint::Format(Some(Format::Evt2)))
            .words(" does not fit")
            .fixed_by(&"drop it".into());
        assert_eq!(
            named.to_string(),
            "the format evt2 does not fit\n  fix: drop it"
        );
        assert_eq!(named.render(&flag), "-x does not fit\n  fix: drop it");
    }
}
