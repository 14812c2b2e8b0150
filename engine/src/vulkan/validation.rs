//! The Khronos validation layer on request: `RESHIFT_VULKAN_VALIDATION=1` (or `sync`) loads
//! `VK_LAYER_KHRONOS_validation` with synchronization validation, `=best-practices` adds the
//! best-practice checks. Both are enabled on instance creation through
//! `VkValidationFeaturesEXT`, so no `vk_layer_settings.txt` is needed. A debug-utils messenger
//! collects every warning and error; [`Validation::check`] turns the first error not yet
//! reported (an invalid use or a synchronization hazard) into a [`VulkanError::Validation`],
//! and the submission paths call it after each wait.

use std::ffi::{CStr, c_char, c_void};
use std::sync::{Mutex, MutexGuard};

use ash::vk;

use super::error::{VulkanError, api};

/// The environment variable that turns validation on: `1` or `sync`, or `best-practices`.
pub const VALIDATION_ENV: &str = "RESHIFT_VULKAN_VALIDATION";

const LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Which checks the validation layer runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Checks {
    /// No layer.
    #[default]
    Off,
    /// Core validation and synchronization validation.
    Sync,
    /// As [`Checks::Sync`], plus the best-practice checks (warnings, e.g. on allocations).
    BestPractices,
}

impl Checks {
    /// The checks [`VALIDATION_ENV`] asks for (unset, empty or `0`: none).
    pub fn from_env() -> Result<Checks, VulkanError> {
        Checks::parse(std::env::var(VALIDATION_ENV).ok().as_deref())
    }

    fn parse(value: Option<&str>) -> Result<Checks, VulkanError> {
        match value.map(str::trim) {
            None | Some("" | "0") => Ok(Checks::Off),
            Some("1" | "sync") => Ok(Checks::Sync),
            Some("best-practices") => Ok(Checks::BestPractices),
            Some(other) => Err(VulkanError::BadSetting(format!(
                "{VALIDATION_ENV}={other:?}: expected 0, 1, sync or best-practices"
            ))),
        }
    }

    fn features(self) -> &'static [vk::ValidationFeatureEnableEXT] {
        use vk::ValidationFeatureEnableEXT as E;
        match self {
            Checks::Off => &[],
            Checks::Sync => &[E::SYNCHRONIZATION_VALIDATION],
            Checks::BestPractices => &[E::SYNCHRONIZATION_VALIDATION, E::BEST_PRACTICES],
        }
    }
}

/// How grave a collected message is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    Warning,
    Error,
}

/// One message of the validation layer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Message {
    pub severity: Severity,
    /// The layer's message id, e.g. `SYNC-HAZARD-READ-AFTER-WRITE`.
    pub id: String,
    pub text: String,
}

/// What the messenger collected, and how many of its messages were already reported.
#[derive(Default)]
struct Log {
    messages: Vec<Message>,
    reported: usize,
}

/// The layer's state on an instance: its messenger and the messages collected.
pub(crate) struct Validation {
    loader: ash::ext::debug_utils::Instance,
    messenger: vk::DebugUtilsMessengerEXT,
    /// Boxed: the messenger holds its address until `destroy`.
    log: Box<Mutex<Log>>,
}

/// The layer name and instance extensions to enable for `checks`, after checking the layer is
/// installed.
pub(crate) fn requirements(
    entry: &ash::Entry,
    checks: Checks,
) -> Result<(Vec<*const c_char>, Vec<*const c_char>), VulkanError> {
    if checks == Checks::Off {
        return Ok((Vec::new(), Vec::new()));
    }
    // SAFETY: a loaded entry.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .map_err(api("vkEnumerateInstanceLayerProperties"))?;
    if !layers
        .iter()
        .any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == LAYER))
    {
        return Err(VulkanError::NoValidationLayer);
    }
    Ok((
        vec![LAYER.as_ptr()],
        vec![
            ash::ext::debug_utils::NAME.as_ptr(),
            ash::ext::validation_features::NAME.as_ptr(),
        ],
    ))
}

/// The `VkValidationFeaturesEXT` to chain into the instance create info for `checks`.
pub(crate) fn features(checks: Checks) -> vk::ValidationFeaturesEXT<'static> {
    vk::ValidationFeaturesEXT::default().enabled_validation_features(checks.features())
}

impl Validation {
    /// The messenger on `instance`, created with the layer and extensions of [`requirements`].
    pub(crate) fn new(
        entry: &ash::Entry,
        instance: &ash::Instance,
    ) -> Result<Validation, VulkanError> {
        use vk::DebugUtilsMessageSeverityFlagsEXT as S;
        use vk::DebugUtilsMessageTypeFlagsEXT as T;
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let log: Box<Mutex<Log>> = Box::default();
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(S::WARNING | S::ERROR)
            .message_type(T::GENERAL | T::VALIDATION | T::PERFORMANCE)
            .pfn_user_callback(Some(collect))
            .user_data(&*log as *const Mutex<Log> as *mut c_void);
        // SAFETY: the log outlives the messenger (`destroy` runs before it is dropped).
        let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
            .map_err(api("vkCreateDebugUtilsMessengerEXT"))?;
        Ok(Validation {
            loader,
            messenger,
            log,
        })
    }

    fn log(&self) -> MutexGuard<'_, Log> {
        self.log.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Every message collected so far.
    pub(crate) fn messages(&self) -> Vec<Message> {
        self.log().messages.clone()
    }

    /// `Err` naming the first error collected since the last check, if any.
    pub(crate) fn check(&self) -> Result<(), VulkanError> {
        let mut log = self.log();
        let fresh = &log.messages[log.reported..];
        let first = fresh
            .iter()
            .find(|m| m.severity == Severity::Error)
            .cloned();
        log.reported = log.messages.len();
        match first {
            Some(m) => Err(VulkanError::Validation(format!("{}: {}", m.id, m.text))),
            None => Ok(()),
        }
    }

    /// Destroys the messenger; call before destroying the instance.
    ///
    /// # Safety
    /// The instance is alive, and nothing uses the messenger afterwards.
    pub(crate) unsafe fn destroy(&self) {
        // SAFETY: as the function's contract.
        unsafe {
            self.loader
                .destroy_debug_utils_messenger(self.messenger, None)
        };
    }
}

/// The messenger's callback: appends the message to the [`Log`] at `user`.
unsafe extern "system" fn collect(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes valid callback data and the `user_data` given at creation, a
    // live `Mutex<Log>`.
    let (data, log) = unsafe { (&*data, &*(user as *const Mutex<Log>)) };
    let text = |s: Option<&CStr>| s.map(|s| s.to_string_lossy().into_owned());
    // SAFETY: the strings are null or NUL-terminated for the duration of the call.
    let (id, message) = unsafe {
        (
            text(data.message_id_name_as_c_str()),
            text(data.message_as_c_str()),
        )
    };
    let severity = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        Severity::Error
    } else {
        Severity::Warning
    };
    log.lock()
        .unwrap_or_else(|e| e.into_inner())
        .messages
        .push(Message {
            severity,
            id: id.unwrap_or_default(),
            // One line: the layer's messages span several.
            text: message.unwrap_or_default().replace('\n', " "),
        });
    vk::FALSE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn setting_parses_or_names_the_bad_value() {
        assert_eq!(Checks::parse(None), Ok(Checks::Off));
        assert_eq!(Checks::parse(Some(" 0 ")), Ok(Checks::Off));
        assert_eq!(Checks::parse(Some("1")), Ok(Checks::Sync));
        assert_eq!(Checks::parse(Some("sync")), Ok(Checks::Sync));
        assert_eq!(
            Checks::parse(Some("best-practices")),
            Ok(Checks::BestPractices)
        );
        let line = Checks::parse(Some("yes")).unwrap_err().to_string();
        assert!(
            line.contains("\"yes\"") && line.contains(VALIDATION_ENV),
            "{line}"
        );
        assert!(Checks::BestPractices.features().len() == 2 && Checks::Off.features().is_empty());
    }
}
