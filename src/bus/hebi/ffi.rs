//! The part of HEBI's C API (`hebi.h`, published in HEBI's `hebi_cpp_api_ros`, Apache-2.0)
//! that the bus uses: the opaque handles, the message reference and metadata structs,
//! the field indices it reads and writes, and the functions, resolved from the library
//! at run time ([`super::library`]). Layouts follow `hebi.h` exactly; the field indices
//! are the enums' (append-only across versions, checked against the metadata at load).

use std::ffi::{c_char, c_void};

pub type StatusCode = i32;
pub const STATUS_SUCCESS: StatusCode = 0;

/// Opaque handles (`HebiLookupPtr`, `HebiGroupPtr`, ...).
pub type LookupPtr = *mut c_void;
pub type EntryListPtr = *mut c_void;
pub type GroupPtr = *mut c_void;
pub type GroupCommandPtr = *mut c_void;
pub type GroupFeedbackPtr = *mut c_void;
pub type CommandPtr = *mut c_void;
pub type FeedbackPtr = *mut c_void;

pub type FeedbackHandler = unsafe extern "C" fn(fbk: GroupFeedbackPtr, user_data: *mut c_void);

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct MacAddress {
    pub bytes: [u8; 6],
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct Vector3f {
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct Quaternionf {
    pub w: f32,
    pub x: f32,
    pub y: f32,
    pub z: f32,
}

/// An angle as whole revolutions plus an offset, rad (`HebiHighResAngleStruct`).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct HighResAngle {
    pub revolutions: i64,
    pub offset: f32,
}

/// `HebiCommandRef` / `HebiFeedbackRef`: pointers into one message's storage. A field
/// is present when its bit in `message_bitfield` is set (bit = the kind's offset from
/// the metadata + the field's index).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct MessageRef {
    pub message_bitfield: *mut i32,
    pub float_fields: *mut f32,
    pub high_res_angle_fields: *mut HighResAngle,
    pub vector3f_fields: *mut Vector3f,
    pub quaternionf_fields: *mut Quaternionf,
    pub uint64_fields: *mut u64,
    pub enum_fields: *mut i32,
    pub bool_fields: *mut bool,
    pub numbered_float_fields: *mut f32,
    pub io_fields: *mut c_void,
    pub led_fields: *mut u32,
    pub reserved: *mut c_void,
}

impl MessageRef {
    pub const NULL: MessageRef = MessageRef {
        message_bitfield: std::ptr::null_mut(),
        float_fields: std::ptr::null_mut(),
        high_res_angle_fields: std::ptr::null_mut(),
        vector3f_fields: std::ptr::null_mut(),
        quaternionf_fields: std::ptr::null_mut(),
        uint64_fields: std::ptr::null_mut(),
        enum_fields: std::ptr::null_mut(),
        bool_fields: std::ptr::null_mut(),
        numbered_float_fields: std::ptr::null_mut(),
        io_fields: std::ptr::null_mut(),
        led_fields: std::ptr::null_mut(),
        reserved: std::ptr::null_mut(),
    };
}

/// `HebiCommandMetadata` / `HebiFeedbackMetadata`: how many fields of each kind the
/// loaded library's messages have and where each kind's presence bits start.
#[repr(C)]
#[derive(Clone, Copy, Default, Debug)]
pub struct Metadata {
    pub float_field_count: u32,
    pub high_res_angle_field_count: u32,
    pub vector3f_field_count: u32,
    pub quaternionf_field_count: u32,
    pub uint64_field_count: u32,
    pub enum_field_count: u32,
    pub bool_field_count: u32,
    pub numbered_float_field_count: u32,
    pub io_field_count: u32,
    pub led_field_count: u32,
    pub string_field_count: u32,
    pub flag_field_count: u32,
    pub float_field_bitfield_offset: u32,
    pub high_res_angle_field_bitfield_offset: u32,
    pub vector3f_field_bitfield_offset: u32,
    pub quaternionf_field_bitfield_offset: u32,
    pub uint64_field_bitfield_offset: u32,
    pub enum_field_bitfield_offset: u32,
    pub bool_field_bitfield_offset: u32,
    pub numbered_float_field_bitfield_offset: u32,
    pub io_field_bitfield_offset: u32,
    pub led_field_bitfield_offset: u32,
    pub string_field_bitfield_offset: u32,
    pub flag_field_bitfield_offset: u32,
    pub numbered_float_relative_offsets: usize,
    pub numbered_float_field_sizes: usize,
    pub io_relative_offsets: usize,
    pub io_field_sizes: usize,
    pub message_bitfield_count: u32,
}

/// Field indices (`hebi.h`'s enums) of the fields the bus uses.
pub mod field {
    // HebiCommandFloatField
    pub const CMD_VELOCITY: u32 = 0;
    pub const CMD_EFFORT: u32 = 1;
    /// PositionKp; the 39 gains and limits after it follow `hebi.h`'s order
    /// (`super::super::gains`).
    pub const CMD_POSITION_KP: u32 = 2;
    // HebiCommandHighResAngleField
    pub const CMD_POSITION: u32 = 0;
    // HebiCommandEnumField
    pub const CMD_CONTROL_STRATEGY: u32 = 0;
    // HebiFeedbackFloatField
    pub const FBK_BOARD_TEMPERATURE: u32 = 0;
    pub const FBK_VOLTAGE: u32 = 2;
    pub const FBK_VELOCITY: u32 = 3;
    pub const FBK_EFFORT: u32 = 4;
    pub const FBK_DEFLECTION: u32 = 7;
    // HebiFeedbackHighResAngleField
    pub const FBK_POSITION: u32 = 0;
    // HebiFeedbackUInt64Field
    pub const FBK_SEQUENCE_NUMBER: u32 = 0;
    pub const FBK_RECEIVE_TIME: u32 = 1;
    pub const FBK_HARDWARE_TRANSMIT_TIME: u32 = 4;
    // HebiFeedbackVector3fField
    pub const FBK_ACCELEROMETER: u32 = 0;
    pub const FBK_GYRO: u32 = 1;
    // HebiFeedbackQuaternionfField
    pub const FBK_ORIENTATION: u32 = 0;
    // HebiFeedbackEnumField
    pub const FBK_COMMAND_LIFETIME_STATE: u32 = 5;
}

/// The functions, as resolved from the library.
#[allow(clippy::type_complexity)]
pub struct Functions {
    pub get_library_version: unsafe extern "C" fn(*mut i32, *mut i32, *mut i32) -> StatusCode,
    pub get_last_error: unsafe extern "C" fn() -> *const c_char,
    pub command_get_metadata: unsafe extern "C" fn(*mut Metadata),
    pub feedback_get_metadata: unsafe extern "C" fn(*mut Metadata),
    pub lookup_create: unsafe extern "C" fn(*const *const c_char, usize) -> LookupPtr,
    pub lookup_release: unsafe extern "C" fn(LookupPtr),
    pub create_lookup_entry_list: unsafe extern "C" fn(LookupPtr) -> EntryListPtr,
    pub lookup_entry_list_get_size: unsafe extern "C" fn(EntryListPtr) -> usize,
    pub lookup_entry_list_get_name:
        unsafe extern "C" fn(EntryListPtr, usize, *mut c_char, *mut usize) -> StatusCode,
    pub lookup_entry_list_get_family:
        unsafe extern "C" fn(EntryListPtr, usize, *mut c_char, *mut usize) -> StatusCode,
    pub lookup_entry_list_get_mac_address:
        unsafe extern "C" fn(EntryListPtr, usize, *mut MacAddress) -> StatusCode,
    pub lookup_entry_list_release: unsafe extern "C" fn(EntryListPtr),
    pub group_create_imitation: unsafe extern "C" fn(usize) -> GroupPtr,
    pub group_create_from_names: unsafe extern "C" fn(
        LookupPtr,
        *const *const c_char,
        usize,
        *const *const c_char,
        usize,
        i32,
    ) -> GroupPtr,
    pub group_create_from_family: unsafe extern "C" fn(LookupPtr, *const c_char, i32) -> GroupPtr,
    pub group_get_size: unsafe extern "C" fn(GroupPtr) -> usize,
    pub group_send_command: unsafe extern "C" fn(GroupPtr, GroupCommandPtr) -> StatusCode,
    pub group_send_command_with_acknowledgement:
        unsafe extern "C" fn(GroupPtr, GroupCommandPtr, i32) -> StatusCode,
    pub group_set_command_lifetime: unsafe extern "C" fn(GroupPtr, i32) -> StatusCode,
    pub group_set_feedback_frequency_hz: unsafe extern "C" fn(GroupPtr, f32) -> StatusCode,
    pub group_register_feedback_handler:
        unsafe extern "C" fn(GroupPtr, FeedbackHandler, *mut c_void) -> StatusCode,
    pub group_clear_feedback_handlers: unsafe extern "C" fn(GroupPtr),
    pub group_release: unsafe extern "C" fn(GroupPtr),
    pub group_command_create: unsafe extern "C" fn(usize) -> GroupCommandPtr,
    pub group_command_get_module_command:
        unsafe extern "C" fn(GroupCommandPtr, usize) -> CommandPtr,
    pub group_command_clear: unsafe extern "C" fn(GroupCommandPtr),
    pub group_command_release: unsafe extern "C" fn(GroupCommandPtr),
    pub group_feedback_get_size: unsafe extern "C" fn(GroupFeedbackPtr) -> usize,
    pub group_feedback_get_module_feedback:
        unsafe extern "C" fn(GroupFeedbackPtr, usize) -> FeedbackPtr,
    pub command_get_reference: unsafe extern "C" fn(CommandPtr, *mut MessageRef),
    pub feedback_get_reference: unsafe extern "C" fn(FeedbackPtr, *mut MessageRef),
}
