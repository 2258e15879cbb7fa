/* bldc_drive_od.h - CANopen object dictionary of the BLDC 5 kW / 48 V drive.
 *
 * GENERATED from bldc_drive.eds by `python -m firmware_protocol.generate`: do not edit.
 * C99, float32 only, 8-bit objects as 16-bit C types (TMS320F28335: char is 16 bits).
 * Macros: OD_<OBJECT>__<SUB>_<FIELD> for records/arrays, OD_<OBJECT>_<FIELD> otherwise.
 * Fields: _INDEX, _SUB, _TYPE (CiA 301 code), _CTYPE, _ACCESS, _PDO (1 = mappable),
 * _DEFAULT, _MIN/_MAX (static limits, inclusive), _REF (index<<16 | sub<<8 | bits).
 * Units are given in the comments. Cross-object rules are listed at the end. */
#ifndef BLDC_DRIVE_OD_H
#define BLDC_DRIVE_OD_H

#include <stdint.h>

/* CiA 301 data type codes */
#define OD_TYPE_BOOL                                             0x0001u
#define OD_TYPE_I8                                               0x0002u
#define OD_TYPE_I16                                              0x0003u
#define OD_TYPE_I32                                              0x0004u
#define OD_TYPE_U8                                               0x0005u
#define OD_TYPE_U16                                              0x0006u
#define OD_TYPE_U32                                              0x0007u
#define OD_TYPE_REAL32                                           0x0008u
#define OD_TYPE_VISIBLE_STRING                                   0x0009u
#define OD_TYPE_OCTET_STRING                                     0x000Au
#define OD_TYPE_DOMAIN                                           0x000Fu

/* Access: bit0 readable, bit1 writable, bit2 constant */
#define OD_ACCESS_RO                                             0x1u
#define OD_ACCESS_WO                                             0x2u
#define OD_ACCESS_RW                                             0x3u
#define OD_ACCESS_CONST                                          0x5u

/* SDO abort codes of the value checks (CiA 301) */
#define OD_ABORT_INVALID_VALUE                                   0x06090030UL
#define OD_ABORT_VALUE_TOO_HIGH                                  0x06090031UL
#define OD_ABORT_VALUE_TOO_LOW                                   0x06090032UL
#define OD_ABORT_READ_ONLY                                       0x06010002UL
#define OD_ABORT_STATE                                           0x08000022UL

/* Device */
#define OD_DEFAULT_NODE_ID                                       1u
#define OD_NR_OF_RXPDO                                           2u
#define OD_NR_OF_TXPDO                                           4u


/* ---- 0x1000 device_type ---- */
/* 0x1000:00 device_type UNSIGNED32 ro - CiA 402 drive: bits 15..0 device profile number 402 (0x0192), bits 23..16 type 0x02 servo drive */
#define OD_DEVICE_TYPE_INDEX                                     0x1000u
#define OD_DEVICE_TYPE_SUB                                       0x00u
#define OD_DEVICE_TYPE_TYPE                                      OD_TYPE_U32
#define OD_DEVICE_TYPE_CTYPE                                     uint32_t
#define OD_DEVICE_TYPE_ACCESS                                    OD_ACCESS_RO
#define OD_DEVICE_TYPE_PDO                                       0u
#define OD_DEVICE_TYPE_DEFAULT                                   0x00020192UL
#define OD_DEVICE_TYPE_REF                                       0x10000020UL

/* ---- 0x1001 error_register ---- */
/* 0x1001:00 error_register UNSIGNED8 ro - bit0 generic, bit1 current, bit2 voltage, bit3 temperature, bit4 communication */
#define OD_ERROR_REGISTER_INDEX                                  0x1001u
#define OD_ERROR_REGISTER_SUB                                    0x00u
#define OD_ERROR_REGISTER_TYPE                                   OD_TYPE_U8
#define OD_ERROR_REGISTER_CTYPE                                  uint16_t
#define OD_ERROR_REGISTER_ACCESS                                 OD_ACCESS_RO
#define OD_ERROR_REGISTER_PDO                                    1u
#define OD_ERROR_REGISTER_DEFAULT                                0u
#define OD_ERROR_REGISTER_REF                                    0x10010008UL

/* ---- 0x1003 pre_defined_error_field ---- */
#define OD_PRE_DEFINED_ERROR_FIELD_INDEX                         0x1003u
/* 0x1003:00 pre_defined_error_field.number_of_errors UNSIGNED8 rw - errors in the history, write 0 to clear it */
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_INDEX       0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_SUB         0x00u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_TYPE        OD_TYPE_U8
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_CTYPE       uint16_t
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_ACCESS      OD_ACCESS_RW
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_PDO         0u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_DEFAULT     0u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_MIN         0u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_MAX         8u
#define OD_PRE_DEFINED_ERROR_FIELD__NUMBER_OF_ERRORS_REF         0x10030008UL
/* 0x1003:01 pre_defined_error_field.standard_error_field_1 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_SUB   0x01u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_1_REF   0x10030120UL
/* 0x1003:02 pre_defined_error_field.standard_error_field_2 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_SUB   0x02u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_2_REF   0x10030220UL
/* 0x1003:03 pre_defined_error_field.standard_error_field_3 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_SUB   0x03u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_3_REF   0x10030320UL
/* 0x1003:04 pre_defined_error_field.standard_error_field_4 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_SUB   0x04u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_4_REF   0x10030420UL
/* 0x1003:05 pre_defined_error_field.standard_error_field_5 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_SUB   0x05u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_5_REF   0x10030520UL
/* 0x1003:06 pre_defined_error_field.standard_error_field_6 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_SUB   0x06u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_6_REF   0x10030620UL
/* 0x1003:07 pre_defined_error_field.standard_error_field_7 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_SUB   0x07u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_7_REF   0x10030720UL
/* 0x1003:08 pre_defined_error_field.standard_error_field_8 UNSIGNED32 ro - EMCY error code (bits 15..0) and manufacturer info (bits 31..16), 1 = newest */
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_INDEX 0x1003u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_SUB   0x08u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_TYPE  OD_TYPE_U32
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_CTYPE uint32_t
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_ACCESS OD_ACCESS_RO
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_PDO   0u
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_DEFAULT 0x00000000UL
#define OD_PRE_DEFINED_ERROR_FIELD__STANDARD_ERROR_FIELD_8_REF   0x10030820UL

/* ---- 0x1005 cob_id_sync ---- */
/* 0x1005:00 cob_id_sync UNSIGNED32 rw - COB-ID of the SYNC message this node consumes (bits 10..0; bit 30 "generate" refused: the drive is no SYNC producer; bit 29 refused: 11-bit only; bit 31 ignored) */
#define OD_COB_ID_SYNC_INDEX                                     0x1005u
#define OD_COB_ID_SYNC_SUB                                       0x00u
#define OD_COB_ID_SYNC_TYPE                                      OD_TYPE_U32
#define OD_COB_ID_SYNC_CTYPE                                     uint32_t
#define OD_COB_ID_SYNC_ACCESS                                    OD_ACCESS_RW
#define OD_COB_ID_SYNC_PDO                                       0u
#define OD_COB_ID_SYNC_DEFAULT                                   0x00000080UL
#define OD_COB_ID_SYNC_REF                                       0x10050020UL

/* ---- 0x1008 manufacturer_device_name ---- */
/* 0x1008:00 manufacturer_device_name VISIBLE_STRING const */
#define OD_MANUFACTURER_DEVICE_NAME_INDEX                        0x1008u
#define OD_MANUFACTURER_DEVICE_NAME_SUB                          0x00u
#define OD_MANUFACTURER_DEVICE_NAME_TYPE                         OD_TYPE_VISIBLE_STRING
#define OD_MANUFACTURER_DEVICE_NAME_ACCESS                       OD_ACCESS_CONST
#define OD_MANUFACTURER_DEVICE_NAME_PDO                          0u
#define OD_MANUFACTURER_DEVICE_NAME_DEFAULT                      "BLDC 5kW 48V drive"

/* ---- 0x1009 hardware_version ---- */
/* 0x1009:00 hardware_version VISIBLE_STRING const */
#define OD_HARDWARE_VERSION_INDEX                                0x1009u
#define OD_HARDWARE_VERSION_SUB                                  0x00u
#define OD_HARDWARE_VERSION_TYPE                                 OD_TYPE_VISIBLE_STRING
#define OD_HARDWARE_VERSION_ACCESS                               OD_ACCESS_CONST
#define OD_HARDWARE_VERSION_PDO                                  0u
#define OD_HARDWARE_VERSION_DEFAULT                              "F28335 rev A"

/* ---- 0x100A software_version ---- */
/* 0x100A:00 software_version VISIBLE_STRING const */
#define OD_SOFTWARE_VERSION_INDEX                                0x100Au
#define OD_SOFTWARE_VERSION_SUB                                  0x00u
#define OD_SOFTWARE_VERSION_TYPE                                 OD_TYPE_VISIBLE_STRING
#define OD_SOFTWARE_VERSION_ACCESS                               OD_ACCESS_CONST
#define OD_SOFTWARE_VERSION_PDO                                  0u
#define OD_SOFTWARE_VERSION_DEFAULT                              "0.1.0"

/* ---- 0x1010 store_parameters ---- */
#define OD_STORE_PARAMETERS_INDEX                                0x1010u
/* 0x1010:00 store_parameters.highest_sub_index UNSIGNED8 const */
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_INDEX             0x1010u
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_SUB               0x00u
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_TYPE              OD_TYPE_U8
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_CTYPE             uint16_t
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_ACCESS            OD_ACCESS_CONST
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_PDO               0u
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_DEFAULT           1u
#define OD_STORE_PARAMETERS__HIGHEST_SUB_INDEX_REF               0x10100008UL
/* 0x1010:01 store_parameters.save_all UNSIGNED32 rw - write 0x65766173 (save) to store all parameters, read: bit0 = saves on command */
#define OD_STORE_PARAMETERS__SAVE_ALL_INDEX                      0x1010u
#define OD_STORE_PARAMETERS__SAVE_ALL_SUB                        0x01u
#define OD_STORE_PARAMETERS__SAVE_ALL_TYPE                       OD_TYPE_U32
#define OD_STORE_PARAMETERS__SAVE_ALL_CTYPE                      uint32_t
#define OD_STORE_PARAMETERS__SAVE_ALL_ACCESS                     OD_ACCESS_RW
#define OD_STORE_PARAMETERS__SAVE_ALL_PDO                        0u
#define OD_STORE_PARAMETERS__SAVE_ALL_DEFAULT                    0x00000001UL
#define OD_STORE_PARAMETERS__SAVE_ALL_REF                        0x10100120UL

/* ---- 0x1011 restore_default_parameters ---- */
#define OD_RESTORE_DEFAULT_PARAMETERS_INDEX                      0x1011u
/* 0x1011:00 restore_default_parameters.highest_sub_index UNSIGNED8 const */
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_INDEX   0x1011u
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_SUB     0x00u
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_TYPE    OD_TYPE_U8
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_CTYPE   uint16_t
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_ACCESS  OD_ACCESS_CONST
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_PDO     0u
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_DEFAULT 1u
#define OD_RESTORE_DEFAULT_PARAMETERS__HIGHEST_SUB_INDEX_REF     0x10110008UL
/* 0x1011:01 restore_default_parameters.restore_all UNSIGNED32 rw - write 0x64616F6C (load) to restore defaults, applied after reset node */
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_INDEX         0x1011u
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_SUB           0x01u
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_TYPE          OD_TYPE_U32
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_CTYPE         uint32_t
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_ACCESS        OD_ACCESS_RW
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_PDO           0u
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_DEFAULT       0x00000001UL
#define OD_RESTORE_DEFAULT_PARAMETERS__RESTORE_ALL_REF           0x10110120UL

/* ---- 0x1014 cob_id_emcy ---- */
/* 0x1014:00 cob_id_emcy UNSIGNED32 rw - COB-ID of the emergency message */
#define OD_COB_ID_EMCY_INDEX                                     0x1014u
#define OD_COB_ID_EMCY_SUB                                       0x00u
#define OD_COB_ID_EMCY_TYPE                                      OD_TYPE_U32
#define OD_COB_ID_EMCY_CTYPE                                     uint32_t
#define OD_COB_ID_EMCY_ACCESS                                    OD_ACCESS_RW
#define OD_COB_ID_EMCY_PDO                                       0u
#define OD_COB_ID_EMCY_DEFAULT_NODEID_OFFSET                     0x00000080UL /* default = offset + node-ID */
#define OD_COB_ID_EMCY_DEFAULT(node_id)                          (OD_COB_ID_EMCY_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_COB_ID_EMCY_REF                                       0x10140020UL

/* ---- 0x1016 consumer_heartbeat_time ---- */
#define OD_CONSUMER_HEARTBEAT_TIME_INDEX                         0x1016u
/* 0x1016:00 consumer_heartbeat_time.highest_sub_index UNSIGNED8 const */
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_INDEX      0x1016u
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_SUB        0x00u
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_TYPE       OD_TYPE_U8
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_CTYPE      uint16_t
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_ACCESS     OD_ACCESS_CONST
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_PDO        0u
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_DEFAULT    4u
#define OD_CONSUMER_HEARTBEAT_TIME__HIGHEST_SUB_INDEX_REF        0x10160008UL
/* 0x1016:01 consumer_heartbeat_time.consumer_1 UNSIGNED32 rw [ms] - node-ID (1..127) in bits 23..16, heartbeat time in ms in bits 15..0, time 0 = entry off; one entry per node (0x06040043) */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_INDEX             0x1016u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_SUB               0x01u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_TYPE              OD_TYPE_U32
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_CTYPE             uint32_t
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_ACCESS            OD_ACCESS_RW
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_PDO               0u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_DEFAULT           0x00000000UL /* ms */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_1_REF               0x10160120UL
/* 0x1016:02 consumer_heartbeat_time.consumer_2 UNSIGNED32 rw [ms] - node-ID (1..127) in bits 23..16, heartbeat time in ms in bits 15..0, time 0 = entry off; one entry per node (0x06040043) */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_INDEX             0x1016u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_SUB               0x02u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_TYPE              OD_TYPE_U32
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_CTYPE             uint32_t
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_ACCESS            OD_ACCESS_RW
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_PDO               0u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_DEFAULT           0x00000000UL /* ms */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_2_REF               0x10160220UL
/* 0x1016:03 consumer_heartbeat_time.consumer_3 UNSIGNED32 rw [ms] - node-ID (1..127) in bits 23..16, heartbeat time in ms in bits 15..0, time 0 = entry off; one entry per node (0x06040043) */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_INDEX             0x1016u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_SUB               0x03u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_TYPE              OD_TYPE_U32
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_CTYPE             uint32_t
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_ACCESS            OD_ACCESS_RW
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_PDO               0u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_DEFAULT           0x00000000UL /* ms */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_3_REF               0x10160320UL
/* 0x1016:04 consumer_heartbeat_time.consumer_4 UNSIGNED32 rw [ms] - node-ID (1..127) in bits 23..16, heartbeat time in ms in bits 15..0, time 0 = entry off; one entry per node (0x06040043) */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_INDEX             0x1016u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_SUB               0x04u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_TYPE              OD_TYPE_U32
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_CTYPE             uint32_t
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_ACCESS            OD_ACCESS_RW
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_PDO               0u
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_DEFAULT           0x00000000UL /* ms */
#define OD_CONSUMER_HEARTBEAT_TIME__CONSUMER_4_REF               0x10160420UL

/* ---- 0x1017 producer_heartbeat_time ---- */
/* 0x1017:00 producer_heartbeat_time UNSIGNED16 rw [ms] - heartbeat period, 0 = off */
#define OD_PRODUCER_HEARTBEAT_TIME_INDEX                         0x1017u
#define OD_PRODUCER_HEARTBEAT_TIME_SUB                           0x00u
#define OD_PRODUCER_HEARTBEAT_TIME_TYPE                          OD_TYPE_U16
#define OD_PRODUCER_HEARTBEAT_TIME_CTYPE                         uint16_t
#define OD_PRODUCER_HEARTBEAT_TIME_ACCESS                        OD_ACCESS_RW
#define OD_PRODUCER_HEARTBEAT_TIME_PDO                           0u
#define OD_PRODUCER_HEARTBEAT_TIME_DEFAULT                       100u /* ms */
#define OD_PRODUCER_HEARTBEAT_TIME_MIN                           0u /* ms */
#define OD_PRODUCER_HEARTBEAT_TIME_MAX                           60000u /* ms */
#define OD_PRODUCER_HEARTBEAT_TIME_REF                           0x10170010UL

/* ---- 0x1018 identity ---- */
#define OD_IDENTITY_INDEX                                        0x1018u
/* 0x1018:00 identity.highest_sub_index UNSIGNED8 const */
#define OD_IDENTITY__HIGHEST_SUB_INDEX_INDEX                     0x1018u
#define OD_IDENTITY__HIGHEST_SUB_INDEX_SUB                       0x00u
#define OD_IDENTITY__HIGHEST_SUB_INDEX_TYPE                      OD_TYPE_U8
#define OD_IDENTITY__HIGHEST_SUB_INDEX_CTYPE                     uint16_t
#define OD_IDENTITY__HIGHEST_SUB_INDEX_ACCESS                    OD_ACCESS_CONST
#define OD_IDENTITY__HIGHEST_SUB_INDEX_PDO                       0u
#define OD_IDENTITY__HIGHEST_SUB_INDEX_DEFAULT                   4u
#define OD_IDENTITY__HIGHEST_SUB_INDEX_REF                       0x10180008UL
/* 0x1018:01 identity.vendor_id UNSIGNED32 ro - no CiA vendor ID assigned */
#define OD_IDENTITY__VENDOR_ID_INDEX                             0x1018u
#define OD_IDENTITY__VENDOR_ID_SUB                               0x01u
#define OD_IDENTITY__VENDOR_ID_TYPE                              OD_TYPE_U32
#define OD_IDENTITY__VENDOR_ID_CTYPE                             uint32_t
#define OD_IDENTITY__VENDOR_ID_ACCESS                            OD_ACCESS_RO
#define OD_IDENTITY__VENDOR_ID_PDO                               0u
#define OD_IDENTITY__VENDOR_ID_DEFAULT                           0x00000000UL
#define OD_IDENTITY__VENDOR_ID_REF                               0x10180120UL
/* 0x1018:02 identity.product_code UNSIGNED32 ro */
#define OD_IDENTITY__PRODUCT_CODE_INDEX                          0x1018u
#define OD_IDENTITY__PRODUCT_CODE_SUB                            0x02u
#define OD_IDENTITY__PRODUCT_CODE_TYPE                           OD_TYPE_U32
#define OD_IDENTITY__PRODUCT_CODE_CTYPE                          uint32_t
#define OD_IDENTITY__PRODUCT_CODE_ACCESS                         OD_ACCESS_RO
#define OD_IDENTITY__PRODUCT_CODE_PDO                            0u
#define OD_IDENTITY__PRODUCT_CODE_DEFAULT                        0x00005048UL
#define OD_IDENTITY__PRODUCT_CODE_REF                            0x10180220UL
/* 0x1018:03 identity.revision_number UNSIGNED32 ro */
#define OD_IDENTITY__REVISION_NUMBER_INDEX                       0x1018u
#define OD_IDENTITY__REVISION_NUMBER_SUB                         0x03u
#define OD_IDENTITY__REVISION_NUMBER_TYPE                        OD_TYPE_U32
#define OD_IDENTITY__REVISION_NUMBER_CTYPE                       uint32_t
#define OD_IDENTITY__REVISION_NUMBER_ACCESS                      OD_ACCESS_RO
#define OD_IDENTITY__REVISION_NUMBER_PDO                         0u
#define OD_IDENTITY__REVISION_NUMBER_DEFAULT                     0x00010000UL
#define OD_IDENTITY__REVISION_NUMBER_REF                         0x10180320UL
/* 0x1018:04 identity.serial_number UNSIGNED32 ro */
#define OD_IDENTITY__SERIAL_NUMBER_INDEX                         0x1018u
#define OD_IDENTITY__SERIAL_NUMBER_SUB                           0x04u
#define OD_IDENTITY__SERIAL_NUMBER_TYPE                          OD_TYPE_U32
#define OD_IDENTITY__SERIAL_NUMBER_CTYPE                         uint32_t
#define OD_IDENTITY__SERIAL_NUMBER_ACCESS                        OD_ACCESS_RO
#define OD_IDENTITY__SERIAL_NUMBER_PDO                           0u
#define OD_IDENTITY__SERIAL_NUMBER_DEFAULT                       0x00000001UL
#define OD_IDENTITY__SERIAL_NUMBER_REF                           0x10180420UL

/* ---- 0x1200 sdo_server_1 ---- */
#define OD_SDO_SERVER_1_INDEX                                    0x1200u
/* 0x1200:00 sdo_server_1.highest_sub_index UNSIGNED8 const */
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_INDEX                 0x1200u
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_SUB                   0x00u
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_TYPE                  OD_TYPE_U8
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_CTYPE                 uint16_t
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_ACCESS                OD_ACCESS_CONST
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_PDO                   0u
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_DEFAULT               2u
#define OD_SDO_SERVER_1__HIGHEST_SUB_INDEX_REF                   0x12000008UL
/* 0x1200:01 sdo_server_1.cob_id_client_to_server UNSIGNED32 ro */
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_INDEX           0x1200u
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_SUB             0x01u
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_TYPE            OD_TYPE_U32
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_CTYPE           uint32_t
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_ACCESS          OD_ACCESS_RO
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_PDO             0u
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_DEFAULT_NODEID_OFFSET 0x00000600UL /* default = offset + node-ID */
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_DEFAULT(node_id) (OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_SDO_SERVER_1__COB_ID_CLIENT_TO_SERVER_REF             0x12000120UL
/* 0x1200:02 sdo_server_1.cob_id_server_to_client UNSIGNED32 ro */
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_INDEX           0x1200u
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_SUB             0x02u
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_TYPE            OD_TYPE_U32
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_CTYPE           uint32_t
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_ACCESS          OD_ACCESS_RO
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_PDO             0u
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_DEFAULT_NODEID_OFFSET 0x00000580UL /* default = offset + node-ID */
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_DEFAULT(node_id) (OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_SDO_SERVER_1__COB_ID_SERVER_TO_CLIENT_REF             0x12000220UL

/* ---- 0x1201 sdo_server_2 ---- */
#define OD_SDO_SERVER_2_INDEX                                    0x1201u
/* 0x1201:00 sdo_server_2.highest_sub_index UNSIGNED8 const */
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_INDEX                 0x1201u
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_SUB                   0x00u
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_TYPE                  OD_TYPE_U8
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_CTYPE                 uint16_t
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_ACCESS                OD_ACCESS_CONST
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_PDO                   0u
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_DEFAULT               3u
#define OD_SDO_SERVER_2__HIGHEST_SUB_INDEX_REF                   0x12010008UL
/* 0x1201:01 sdo_server_2.cob_id_client_to_server UNSIGNED32 rw - second SDO channel so a trace upload never blocks status reads, valid for node-ID <= 47 */
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_INDEX           0x1201u
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_SUB             0x01u
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_TYPE            OD_TYPE_U32
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_CTYPE           uint32_t
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_ACCESS          OD_ACCESS_RW
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_PDO             0u
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_DEFAULT_NODEID_OFFSET 0x00000680UL /* default = offset + node-ID */
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_DEFAULT(node_id) (OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_SDO_SERVER_2__COB_ID_CLIENT_TO_SERVER_REF             0x12010120UL
/* 0x1201:02 sdo_server_2.cob_id_server_to_client UNSIGNED32 rw */
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_INDEX           0x1201u
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_SUB             0x02u
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_TYPE            OD_TYPE_U32
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_CTYPE           uint32_t
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_ACCESS          OD_ACCESS_RW
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_PDO             0u
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_DEFAULT_NODEID_OFFSET 0x000006B0UL /* default = offset + node-ID */
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_DEFAULT(node_id) (OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_SDO_SERVER_2__COB_ID_SERVER_TO_CLIENT_REF             0x12010220UL
/* 0x1201:03 sdo_server_2.node_id_of_sdo_client UNSIGNED8 rw */
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_INDEX             0x1201u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_SUB               0x03u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_TYPE              OD_TYPE_U8
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_CTYPE             uint16_t
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_ACCESS            OD_ACCESS_RW
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_PDO               0u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_DEFAULT           0u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_MIN               0u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_MAX               127u
#define OD_SDO_SERVER_2__NODE_ID_OF_SDO_CLIENT_REF               0x12010308UL

/* ---- 0x1400 rpdo1_communication ---- */
#define OD_RPDO1_COMMUNICATION_INDEX                             0x1400u
/* 0x1400:00 rpdo1_communication.highest_sub_index UNSIGNED8 const */
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1400u
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        5u
#define OD_RPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x14000008UL
/* 0x1400:01 rpdo1_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_RPDO1_COMMUNICATION__COB_ID_INDEX                     0x1400u
#define OD_RPDO1_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_RPDO1_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_RPDO1_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_RPDO1_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_RPDO1_COMMUNICATION__COB_ID_PDO                       0u
#define OD_RPDO1_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000200UL /* default = offset + node-ID */
#define OD_RPDO1_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_RPDO1_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_RPDO1_COMMUNICATION__COB_ID_REF                       0x14000120UL
/* 0x1400:02 rpdo1_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1400u
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_RPDO1_COMMUNICATION__TRANSMISSION_TYPE_REF            0x14000208UL
/* 0x1400:03 rpdo1_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_INDEX               0x1400u
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_RPDO1_COMMUNICATION__INHIBIT_TIME_REF                 0x14000310UL
/* 0x1400:04 rpdo1_communication.compatibility_entry UNSIGNED8 rw */
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1400u
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_RPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x14000408UL
/* 0x1400:05 rpdo1_communication.event_timer UNSIGNED16 rw [ms] - deadline monitoring, 0 = off */
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_INDEX                0x1400u
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_DEFAULT              0u /* ms */
#define OD_RPDO1_COMMUNICATION__EVENT_TIMER_REF                  0x14000510UL

/* ---- 0x1401 rpdo2_communication ---- */
#define OD_RPDO2_COMMUNICATION_INDEX                             0x1401u
/* 0x1401:00 rpdo2_communication.highest_sub_index UNSIGNED8 const */
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1401u
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        5u
#define OD_RPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x14010008UL
/* 0x1401:01 rpdo2_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_RPDO2_COMMUNICATION__COB_ID_INDEX                     0x1401u
#define OD_RPDO2_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_RPDO2_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_RPDO2_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_RPDO2_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_RPDO2_COMMUNICATION__COB_ID_PDO                       0u
#define OD_RPDO2_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000300UL /* default = offset + node-ID */
#define OD_RPDO2_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_RPDO2_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_RPDO2_COMMUNICATION__COB_ID_REF                       0x14010120UL
/* 0x1401:02 rpdo2_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1401u
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_RPDO2_COMMUNICATION__TRANSMISSION_TYPE_REF            0x14010208UL
/* 0x1401:03 rpdo2_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_INDEX               0x1401u
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_RPDO2_COMMUNICATION__INHIBIT_TIME_REF                 0x14010310UL
/* 0x1401:04 rpdo2_communication.compatibility_entry UNSIGNED8 rw */
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1401u
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_RPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x14010408UL
/* 0x1401:05 rpdo2_communication.event_timer UNSIGNED16 rw [ms] - deadline monitoring, 0 = off */
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_INDEX                0x1401u
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_DEFAULT              0u /* ms */
#define OD_RPDO2_COMMUNICATION__EVENT_TIMER_REF                  0x14010510UL

/* ---- 0x1600 rpdo1_mapping ---- */
#define OD_RPDO1_MAPPING_INDEX                                   0x1600u
/* 0x1600:00 rpdo1_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1600u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       2u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_RPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x16000008UL
/* 0x1600:01 rpdo1_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x60400010UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_1_REF                    0x16000120UL
/* 0x1600:02 rpdo1_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x60FF0020UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_2_REF                    0x16000220UL
/* 0x1600:03 rpdo1_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_3_REF                    0x16000320UL
/* 0x1600:04 rpdo1_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_4_REF                    0x16000420UL
/* 0x1600:05 rpdo1_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_5_REF                    0x16000520UL
/* 0x1600:06 rpdo1_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_6_REF                    0x16000620UL
/* 0x1600:07 rpdo1_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_7_REF                    0x16000720UL
/* 0x1600:08 rpdo1_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1600u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_RPDO1_MAPPING__MAPPED_OBJECT_8_REF                    0x16000820UL

/* ---- 0x1601 rpdo2_mapping ---- */
#define OD_RPDO2_MAPPING_INDEX                                   0x1601u
/* 0x1601:00 rpdo2_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1601u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       1u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_RPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x16010008UL
/* 0x1601:01 rpdo2_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x20300120UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_1_REF                    0x16010120UL
/* 0x1601:02 rpdo2_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_2_REF                    0x16010220UL
/* 0x1601:03 rpdo2_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_3_REF                    0x16010320UL
/* 0x1601:04 rpdo2_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_4_REF                    0x16010420UL
/* 0x1601:05 rpdo2_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_5_REF                    0x16010520UL
/* 0x1601:06 rpdo2_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_6_REF                    0x16010620UL
/* 0x1601:07 rpdo2_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_7_REF                    0x16010720UL
/* 0x1601:08 rpdo2_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1601u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_RPDO2_MAPPING__MAPPED_OBJECT_8_REF                    0x16010820UL

/* ---- 0x1800 tpdo1_communication ---- */
#define OD_TPDO1_COMMUNICATION_INDEX                             0x1800u
/* 0x1800:00 tpdo1_communication.highest_sub_index UNSIGNED8 const */
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1800u
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        6u
#define OD_TPDO1_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x18000008UL
/* 0x1800:01 tpdo1_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_TPDO1_COMMUNICATION__COB_ID_INDEX                     0x1800u
#define OD_TPDO1_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_TPDO1_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_TPDO1_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_TPDO1_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__COB_ID_PDO                       0u
#define OD_TPDO1_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000180UL /* default = offset + node-ID */
#define OD_TPDO1_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_TPDO1_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_TPDO1_COMMUNICATION__COB_ID_REF                       0x18000120UL
/* 0x1800:02 tpdo1_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1800u
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_TPDO1_COMMUNICATION__TRANSMISSION_TYPE_REF            0x18000208UL
/* 0x1800:03 tpdo1_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_INDEX               0x1800u
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_TPDO1_COMMUNICATION__INHIBIT_TIME_REF                 0x18000310UL
/* 0x1800:04 tpdo1_communication.compatibility_entry UNSIGNED8 rw */
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1800u
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_TPDO1_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x18000408UL
/* 0x1800:05 tpdo1_communication.event_timer UNSIGNED16 rw [ms] - period of the event-driven TPDO, 0 = off */
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_INDEX                0x1800u
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_DEFAULT              10u /* ms */
#define OD_TPDO1_COMMUNICATION__EVENT_TIMER_REF                  0x18000510UL
/* 0x1800:06 tpdo1_communication.sync_start_value UNSIGNED8 rw */
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_INDEX           0x1800u
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_SUB             0x06u
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_TYPE            OD_TYPE_U8
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_CTYPE           uint16_t
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_ACCESS          OD_ACCESS_RW
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_PDO             0u
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_DEFAULT         0u
#define OD_TPDO1_COMMUNICATION__SYNC_START_VALUE_REF             0x18000608UL

/* ---- 0x1801 tpdo2_communication ---- */
#define OD_TPDO2_COMMUNICATION_INDEX                             0x1801u
/* 0x1801:00 tpdo2_communication.highest_sub_index UNSIGNED8 const */
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1801u
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        6u
#define OD_TPDO2_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x18010008UL
/* 0x1801:01 tpdo2_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_TPDO2_COMMUNICATION__COB_ID_INDEX                     0x1801u
#define OD_TPDO2_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_TPDO2_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_TPDO2_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_TPDO2_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__COB_ID_PDO                       0u
#define OD_TPDO2_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000280UL /* default = offset + node-ID */
#define OD_TPDO2_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_TPDO2_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_TPDO2_COMMUNICATION__COB_ID_REF                       0x18010120UL
/* 0x1801:02 tpdo2_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1801u
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_TPDO2_COMMUNICATION__TRANSMISSION_TYPE_REF            0x18010208UL
/* 0x1801:03 tpdo2_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_INDEX               0x1801u
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_TPDO2_COMMUNICATION__INHIBIT_TIME_REF                 0x18010310UL
/* 0x1801:04 tpdo2_communication.compatibility_entry UNSIGNED8 rw */
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1801u
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_TPDO2_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x18010408UL
/* 0x1801:05 tpdo2_communication.event_timer UNSIGNED16 rw [ms] - period of the event-driven TPDO, 0 = off */
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_INDEX                0x1801u
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_DEFAULT              1u /* ms */
#define OD_TPDO2_COMMUNICATION__EVENT_TIMER_REF                  0x18010510UL
/* 0x1801:06 tpdo2_communication.sync_start_value UNSIGNED8 rw */
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_INDEX           0x1801u
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_SUB             0x06u
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_TYPE            OD_TYPE_U8
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_CTYPE           uint16_t
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_ACCESS          OD_ACCESS_RW
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_PDO             0u
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_DEFAULT         0u
#define OD_TPDO2_COMMUNICATION__SYNC_START_VALUE_REF             0x18010608UL

/* ---- 0x1802 tpdo3_communication ---- */
#define OD_TPDO3_COMMUNICATION_INDEX                             0x1802u
/* 0x1802:00 tpdo3_communication.highest_sub_index UNSIGNED8 const */
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1802u
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        6u
#define OD_TPDO3_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x18020008UL
/* 0x1802:01 tpdo3_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_TPDO3_COMMUNICATION__COB_ID_INDEX                     0x1802u
#define OD_TPDO3_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_TPDO3_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_TPDO3_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_TPDO3_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__COB_ID_PDO                       0u
#define OD_TPDO3_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000380UL /* default = offset + node-ID */
#define OD_TPDO3_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_TPDO3_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_TPDO3_COMMUNICATION__COB_ID_REF                       0x18020120UL
/* 0x1802:02 tpdo3_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1802u
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_TPDO3_COMMUNICATION__TRANSMISSION_TYPE_REF            0x18020208UL
/* 0x1802:03 tpdo3_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_INDEX               0x1802u
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_TPDO3_COMMUNICATION__INHIBIT_TIME_REF                 0x18020310UL
/* 0x1802:04 tpdo3_communication.compatibility_entry UNSIGNED8 rw */
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1802u
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_TPDO3_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x18020408UL
/* 0x1802:05 tpdo3_communication.event_timer UNSIGNED16 rw [ms] - period of the event-driven TPDO, 0 = off */
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_INDEX                0x1802u
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_DEFAULT              1u /* ms */
#define OD_TPDO3_COMMUNICATION__EVENT_TIMER_REF                  0x18020510UL
/* 0x1802:06 tpdo3_communication.sync_start_value UNSIGNED8 rw */
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_INDEX           0x1802u
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_SUB             0x06u
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_TYPE            OD_TYPE_U8
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_CTYPE           uint16_t
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_ACCESS          OD_ACCESS_RW
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_PDO             0u
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_DEFAULT         0u
#define OD_TPDO3_COMMUNICATION__SYNC_START_VALUE_REF             0x18020608UL

/* ---- 0x1803 tpdo4_communication ---- */
#define OD_TPDO4_COMMUNICATION_INDEX                             0x1803u
/* 0x1803:00 tpdo4_communication.highest_sub_index UNSIGNED8 const */
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_INDEX          0x1803u
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_SUB            0x00u
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_TYPE           OD_TYPE_U8
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_CTYPE          uint16_t
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_ACCESS         OD_ACCESS_CONST
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_PDO            0u
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_DEFAULT        6u
#define OD_TPDO4_COMMUNICATION__HIGHEST_SUB_INDEX_REF            0x18030008UL
/* 0x1803:01 tpdo4_communication.cob_id UNSIGNED32 rw - bit31 = 1 disables the PDO */
#define OD_TPDO4_COMMUNICATION__COB_ID_INDEX                     0x1803u
#define OD_TPDO4_COMMUNICATION__COB_ID_SUB                       0x01u
#define OD_TPDO4_COMMUNICATION__COB_ID_TYPE                      OD_TYPE_U32
#define OD_TPDO4_COMMUNICATION__COB_ID_CTYPE                     uint32_t
#define OD_TPDO4_COMMUNICATION__COB_ID_ACCESS                    OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__COB_ID_PDO                       0u
#define OD_TPDO4_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET     0x00000480UL /* default = offset + node-ID */
#define OD_TPDO4_COMMUNICATION__COB_ID_DEFAULT(node_id)          (OD_TPDO4_COMMUNICATION__COB_ID_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))
#define OD_TPDO4_COMMUNICATION__COB_ID_REF                       0x18030120UL
/* 0x1803:02 tpdo4_communication.transmission_type UNSIGNED8 rw - 0xFF = event driven (manufacturer) */
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_INDEX          0x1803u
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_SUB            0x02u
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_TYPE           OD_TYPE_U8
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_CTYPE          uint16_t
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_ACCESS         OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_PDO            0u
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_DEFAULT        255u
#define OD_TPDO4_COMMUNICATION__TRANSMISSION_TYPE_REF            0x18030208UL
/* 0x1803:03 tpdo4_communication.inhibit_time UNSIGNED16 rw [100 us] */
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_INDEX               0x1803u
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_SUB                 0x03u
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_TYPE                OD_TYPE_U16
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_CTYPE               uint16_t
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_ACCESS              OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_PDO                 0u
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_DEFAULT             0u /* 100 us */
#define OD_TPDO4_COMMUNICATION__INHIBIT_TIME_REF                 0x18030310UL
/* 0x1803:04 tpdo4_communication.compatibility_entry UNSIGNED8 rw */
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_INDEX        0x1803u
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_SUB          0x04u
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_TYPE         OD_TYPE_U8
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_CTYPE        uint16_t
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_ACCESS       OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_PDO          0u
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_DEFAULT      0u
#define OD_TPDO4_COMMUNICATION__COMPATIBILITY_ENTRY_REF          0x18030408UL
/* 0x1803:05 tpdo4_communication.event_timer UNSIGNED16 rw [ms] - period of the event-driven TPDO, 0 = off */
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_INDEX                0x1803u
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_SUB                  0x05u
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_TYPE                 OD_TYPE_U16
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_CTYPE                uint16_t
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_ACCESS               OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_PDO                  0u
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_DEFAULT              10u /* ms */
#define OD_TPDO4_COMMUNICATION__EVENT_TIMER_REF                  0x18030510UL
/* 0x1803:06 tpdo4_communication.sync_start_value UNSIGNED8 rw */
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_INDEX           0x1803u
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_SUB             0x06u
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_TYPE            OD_TYPE_U8
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_CTYPE           uint16_t
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_ACCESS          OD_ACCESS_RW
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_PDO             0u
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_DEFAULT         0u
#define OD_TPDO4_COMMUNICATION__SYNC_START_VALUE_REF             0x18030608UL

/* ---- 0x1A00 tpdo1_mapping ---- */
#define OD_TPDO1_MAPPING_INDEX                                   0x1A00u
/* 0x1A00:00 tpdo1_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1A00u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       2u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_TPDO1_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x1A000008UL
/* 0x1A00:01 tpdo1_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x60410010UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_1_REF                    0x1A000120UL
/* 0x1A00:02 tpdo1_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x606C0020UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_2_REF                    0x1A000220UL
/* 0x1A00:03 tpdo1_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_3_REF                    0x1A000320UL
/* 0x1A00:04 tpdo1_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_4_REF                    0x1A000420UL
/* 0x1A00:05 tpdo1_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_5_REF                    0x1A000520UL
/* 0x1A00:06 tpdo1_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_6_REF                    0x1A000620UL
/* 0x1A00:07 tpdo1_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_7_REF                    0x1A000720UL
/* 0x1A00:08 tpdo1_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1A00u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_TPDO1_MAPPING__MAPPED_OBJECT_8_REF                    0x1A000820UL

/* ---- 0x1A01 tpdo2_mapping ---- */
#define OD_TPDO2_MAPPING_INDEX                                   0x1A01u
/* 0x1A01:00 tpdo2_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1A01u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       2u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_TPDO2_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x1A010008UL
/* 0x1A01:01 tpdo2_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x20400120UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_1_REF                    0x1A010120UL
/* 0x1A01:02 tpdo2_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x20400520UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_2_REF                    0x1A010220UL
/* 0x1A01:03 tpdo2_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_3_REF                    0x1A010320UL
/* 0x1A01:04 tpdo2_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_4_REF                    0x1A010420UL
/* 0x1A01:05 tpdo2_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_5_REF                    0x1A010520UL
/* 0x1A01:06 tpdo2_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_6_REF                    0x1A010620UL
/* 0x1A01:07 tpdo2_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_7_REF                    0x1A010720UL
/* 0x1A01:08 tpdo2_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1A01u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_TPDO2_MAPPING__MAPPED_OBJECT_8_REF                    0x1A010820UL

/* ---- 0x1A02 tpdo3_mapping ---- */
#define OD_TPDO3_MAPPING_INDEX                                   0x1A02u
/* 0x1A02:00 tpdo3_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1A02u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       2u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_TPDO3_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x1A020008UL
/* 0x1A02:01 tpdo3_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x20400A20UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_1_REF                    0x1A020120UL
/* 0x1A02:02 tpdo3_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x20400B20UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_2_REF                    0x1A020220UL
/* 0x1A02:03 tpdo3_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_3_REF                    0x1A020320UL
/* 0x1A02:04 tpdo3_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_4_REF                    0x1A020420UL
/* 0x1A02:05 tpdo3_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_5_REF                    0x1A020520UL
/* 0x1A02:06 tpdo3_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_6_REF                    0x1A020620UL
/* 0x1A02:07 tpdo3_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_7_REF                    0x1A020720UL
/* 0x1A02:08 tpdo3_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1A02u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_TPDO3_MAPPING__MAPPED_OBJECT_8_REF                    0x1A020820UL

/* ---- 0x1A03 tpdo4_mapping ---- */
#define OD_TPDO4_MAPPING_INDEX                                   0x1A03u
/* 0x1A03:00 tpdo4_mapping.number_of_mapped_objects UNSIGNED8 rw */
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_INDEX         0x1A03u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_SUB           0x00u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_TYPE          OD_TYPE_U8
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_CTYPE         uint16_t
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_ACCESS        OD_ACCESS_RW
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_PDO           0u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_DEFAULT       2u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MIN           0u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_MAX           8u
#define OD_TPDO4_MAPPING__NUMBER_OF_MAPPED_OBJECTS_REF           0x1A030008UL
/* 0x1A03:01 tpdo4_mapping.mapped_object_1 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_SUB                    0x01u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_DEFAULT                0x20400620UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_1_REF                    0x1A030120UL
/* 0x1A03:02 tpdo4_mapping.mapped_object_2 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_SUB                    0x02u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_DEFAULT                0x20400720UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_2_REF                    0x1A030220UL
/* 0x1A03:03 tpdo4_mapping.mapped_object_3 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_SUB                    0x03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_3_REF                    0x1A030320UL
/* 0x1A03:04 tpdo4_mapping.mapped_object_4 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_SUB                    0x04u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_4_REF                    0x1A030420UL
/* 0x1A03:05 tpdo4_mapping.mapped_object_5 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_SUB                    0x05u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_5_REF                    0x1A030520UL
/* 0x1A03:06 tpdo4_mapping.mapped_object_6 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_SUB                    0x06u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_6_REF                    0x1A030620UL
/* 0x1A03:07 tpdo4_mapping.mapped_object_7 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_SUB                    0x07u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_7_REF                    0x1A030720UL
/* 0x1A03:08 tpdo4_mapping.mapped_object_8 UNSIGNED32 rw - index (31..16), sub-index (15..8), bit length (7..0) */
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_INDEX                  0x1A03u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_SUB                    0x08u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_TYPE                   OD_TYPE_U32
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_CTYPE                  uint32_t
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_ACCESS                 OD_ACCESS_RW
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_PDO                    0u
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_DEFAULT                0x00000000UL
#define OD_TPDO4_MAPPING__MAPPED_OBJECT_8_REF                    0x1A030820UL

/* ---- 0x2000 motor ---- */
#define OD_MOTOR_INDEX                                           0x2000u
/* 0x2000:00 motor.highest_sub_index UNSIGNED8 const */
#define OD_MOTOR__HIGHEST_SUB_INDEX_INDEX                        0x2000u
#define OD_MOTOR__HIGHEST_SUB_INDEX_SUB                          0x00u
#define OD_MOTOR__HIGHEST_SUB_INDEX_TYPE                         OD_TYPE_U8
#define OD_MOTOR__HIGHEST_SUB_INDEX_CTYPE                        uint16_t
#define OD_MOTOR__HIGHEST_SUB_INDEX_ACCESS                       OD_ACCESS_CONST
#define OD_MOTOR__HIGHEST_SUB_INDEX_PDO                          0u
#define OD_MOTOR__HIGHEST_SUB_INDEX_DEFAULT                      6u
#define OD_MOTOR__HIGHEST_SUB_INDEX_REF                          0x20000008UL
/* 0x2000:01 motor.R REAL32 rw [Ohm] - phase resistance */
#define OD_MOTOR__R_INDEX                                        0x2000u
#define OD_MOTOR__R_SUB                                          0x01u
#define OD_MOTOR__R_TYPE                                         OD_TYPE_REAL32
#define OD_MOTOR__R_CTYPE                                        float
#define OD_MOTOR__R_ACCESS                                       OD_ACCESS_RW
#define OD_MOTOR__R_PDO                                          0u
#define OD_MOTOR__R_DEFAULT                                      0.0062f /* Ohm */
#define OD_MOTOR__R_MIN                                          0.0001f /* Ohm */
#define OD_MOTOR__R_MAX                                          1.0f /* Ohm */
#define OD_MOTOR__R_CONFIG_ONLY                                  1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__R_REF                                          0x20000120UL
/* 0x2000:02 motor.L REAL32 rw [H] - phase inductance */
#define OD_MOTOR__L_INDEX                                        0x2000u
#define OD_MOTOR__L_SUB                                          0x02u
#define OD_MOTOR__L_TYPE                                         OD_TYPE_REAL32
#define OD_MOTOR__L_CTYPE                                        float
#define OD_MOTOR__L_ACCESS                                       OD_ACCESS_RW
#define OD_MOTOR__L_PDO                                          0u
#define OD_MOTOR__L_DEFAULT                                      1.48e-05f /* H */
#define OD_MOTOR__L_MIN                                          1e-06f /* H */
#define OD_MOTOR__L_MAX                                          0.001f /* H */
#define OD_MOTOR__L_CONFIG_ONLY                                  1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__L_REF                                          0x20000220UL
/* 0x2000:03 motor.K_rpm REAL32 rw [V/rpm] - back-EMF constant, line-to-line */
#define OD_MOTOR__K_RPM_INDEX                                    0x2000u
#define OD_MOTOR__K_RPM_SUB                                      0x03u
#define OD_MOTOR__K_RPM_TYPE                                     OD_TYPE_REAL32
#define OD_MOTOR__K_RPM_CTYPE                                    float
#define OD_MOTOR__K_RPM_ACCESS                                   OD_ACCESS_RW
#define OD_MOTOR__K_RPM_PDO                                      0u
#define OD_MOTOR__K_RPM_DEFAULT                                  0.0125f /* V/rpm */
#define OD_MOTOR__K_RPM_MIN                                      0.0001f /* V/rpm */
#define OD_MOTOR__K_RPM_MAX                                      1.0f /* V/rpm */
#define OD_MOTOR__K_RPM_CONFIG_ONLY                              1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__K_RPM_REF                                      0x20000320UL
/* 0x2000:04 motor.pole_pairs UNSIGNED16 rw [1] */
#define OD_MOTOR__POLE_PAIRS_INDEX                               0x2000u
#define OD_MOTOR__POLE_PAIRS_SUB                                 0x04u
#define OD_MOTOR__POLE_PAIRS_TYPE                                OD_TYPE_U16
#define OD_MOTOR__POLE_PAIRS_CTYPE                               uint16_t
#define OD_MOTOR__POLE_PAIRS_ACCESS                              OD_ACCESS_RW
#define OD_MOTOR__POLE_PAIRS_PDO                                 0u
#define OD_MOTOR__POLE_PAIRS_DEFAULT                             4u /* 1 */
#define OD_MOTOR__POLE_PAIRS_MIN                                 1u /* 1 */
#define OD_MOTOR__POLE_PAIRS_MAX                                 32u /* 1 */
#define OD_MOTOR__POLE_PAIRS_CONFIG_ONLY                         1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__POLE_PAIRS_REF                                 0x20000410UL
/* 0x2000:05 motor.rated_current REAL32 rw [A] */
#define OD_MOTOR__RATED_CURRENT_INDEX                            0x2000u
#define OD_MOTOR__RATED_CURRENT_SUB                              0x05u
#define OD_MOTOR__RATED_CURRENT_TYPE                             OD_TYPE_REAL32
#define OD_MOTOR__RATED_CURRENT_CTYPE                            float
#define OD_MOTOR__RATED_CURRENT_ACCESS                           OD_ACCESS_RW
#define OD_MOTOR__RATED_CURRENT_PDO                              0u
#define OD_MOTOR__RATED_CURRENT_DEFAULT                          100.0f /* A */
#define OD_MOTOR__RATED_CURRENT_MIN                              1.0f /* A */
#define OD_MOTOR__RATED_CURRENT_MAX                              200.0f /* A */
#define OD_MOTOR__RATED_CURRENT_CONFIG_ONLY                      1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__RATED_CURRENT_REF                              0x20000520UL
/* 0x2000:06 motor.V_dc_nominal REAL32 rw [V] - nominal DC-link voltage */
#define OD_MOTOR__V_DC_NOMINAL_INDEX                             0x2000u
#define OD_MOTOR__V_DC_NOMINAL_SUB                               0x06u
#define OD_MOTOR__V_DC_NOMINAL_TYPE                              OD_TYPE_REAL32
#define OD_MOTOR__V_DC_NOMINAL_CTYPE                             float
#define OD_MOTOR__V_DC_NOMINAL_ACCESS                            OD_ACCESS_RW
#define OD_MOTOR__V_DC_NOMINAL_PDO                               0u
#define OD_MOTOR__V_DC_NOMINAL_DEFAULT                           48.0f /* V */
#define OD_MOTOR__V_DC_NOMINAL_MIN                               10.0f /* V */
#define OD_MOTOR__V_DC_NOMINAL_MAX                               100.0f /* V */
#define OD_MOTOR__V_DC_NOMINAL_CONFIG_ONLY                       1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR__V_DC_NOMINAL_REF                               0x20000620UL

/* ---- 0x2010 current_controller ---- */
#define OD_CURRENT_CONTROLLER_INDEX                              0x2010u
/* 0x2010:00 current_controller.highest_sub_index UNSIGNED8 const */
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_INDEX           0x2010u
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_SUB             0x00u
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_TYPE            OD_TYPE_U8
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_CTYPE           uint16_t
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_ACCESS          OD_ACCESS_CONST
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_PDO             0u
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_DEFAULT         10u
#define OD_CURRENT_CONTROLLER__HIGHEST_SUB_INDEX_REF             0x20100008UL
/* 0x2010:01 current_controller.type UNSIGNED8 rw [1] - 0 deadbeat eq.15, 1 PI eq.22, 2 predictive eq.23/25 */
#define OD_CURRENT_CONTROLLER__TYPE_INDEX                        0x2010u
#define OD_CURRENT_CONTROLLER__TYPE_SUB                          0x01u
#define OD_CURRENT_CONTROLLER__TYPE_TYPE                         OD_TYPE_U8
#define OD_CURRENT_CONTROLLER__TYPE_CTYPE                        uint16_t
#define OD_CURRENT_CONTROLLER__TYPE_ACCESS                       OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__TYPE_PDO                          0u
#define OD_CURRENT_CONTROLLER__TYPE_DEFAULT                      0u /* 1 */
#define OD_CURRENT_CONTROLLER__TYPE_MIN                          0u /* 1 */
#define OD_CURRENT_CONTROLLER__TYPE_MAX                          2u /* 1 */
#define OD_CURRENT_CONTROLLER__TYPE_REF                          0x20100108UL
#define OD_CURRENT_CONTROLLER__TYPE_DEADBEAT                     0u
#define OD_CURRENT_CONTROLLER__TYPE_PI                           1u
#define OD_CURRENT_CONTROLLER__TYPE_PREDICTIVE                   2u
/* 0x2010:02 current_controller.L_c REAL32 rw [H] - controller estimate of L, must satisfy 0 < L_c < 2 motor.L */
#define OD_CURRENT_CONTROLLER__L_C_INDEX                         0x2010u
#define OD_CURRENT_CONTROLLER__L_C_SUB                           0x02u
#define OD_CURRENT_CONTROLLER__L_C_TYPE                          OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__L_C_CTYPE                         float
#define OD_CURRENT_CONTROLLER__L_C_ACCESS                        OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__L_C_PDO                           0u
#define OD_CURRENT_CONTROLLER__L_C_DEFAULT                       1.48e-05f /* H */
#define OD_CURRENT_CONTROLLER__L_C_MIN                           1e-08f /* H */
#define OD_CURRENT_CONTROLLER__L_C_MAX                           0.002f /* H */
#define OD_CURRENT_CONTROLLER__L_C_REF                           0x20100220UL
/* 0x2010:03 current_controller.R_c REAL32 rw [Ohm] - controller estimate of R: 0 (Gamma_c = Ts/(2 L_c)) or 1e-4..2 motor.R */
#define OD_CURRENT_CONTROLLER__R_C_INDEX                         0x2010u
#define OD_CURRENT_CONTROLLER__R_C_SUB                           0x03u
#define OD_CURRENT_CONTROLLER__R_C_TYPE                          OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__R_C_CTYPE                         float
#define OD_CURRENT_CONTROLLER__R_C_ACCESS                        OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__R_C_PDO                           0u
#define OD_CURRENT_CONTROLLER__R_C_DEFAULT                       0.0062f /* Ohm */
#define OD_CURRENT_CONTROLLER__R_C_MIN                           0.0f /* Ohm */
#define OD_CURRENT_CONTROLLER__R_C_MAX                           1.0f /* Ohm */
#define OD_CURRENT_CONTROLLER__R_C_MIN_NONZERO                   0.0001f /* Ohm: 0 or >= this */
#define OD_CURRENT_CONTROLLER__R_C_REF                           0x20100320UL
/* 0x2010:04 current_controller.k_p REAL32 rw [V/A] - PI proportional gain k_p,i (eq. 22) */
#define OD_CURRENT_CONTROLLER__K_P_INDEX                         0x2010u
#define OD_CURRENT_CONTROLLER__K_P_SUB                           0x04u
#define OD_CURRENT_CONTROLLER__K_P_TYPE                          OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__K_P_CTYPE                         float
#define OD_CURRENT_CONTROLLER__K_P_ACCESS                        OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__K_P_PDO                           0u
#define OD_CURRENT_CONTROLLER__K_P_DEFAULT                       0.4647f /* V/A */
#define OD_CURRENT_CONTROLLER__K_P_MIN                           0.0f /* V/A */
#define OD_CURRENT_CONTROLLER__K_P_MAX                           100.0f /* V/A */
#define OD_CURRENT_CONTROLLER__K_P_REF                           0x20100420UL
/* 0x2010:05 current_controller.k_i REAL32 rw [V/A] - PI integral gain k_i,i (eq. 22) */
#define OD_CURRENT_CONTROLLER__K_I_INDEX                         0x2010u
#define OD_CURRENT_CONTROLLER__K_I_SUB                           0x05u
#define OD_CURRENT_CONTROLLER__K_I_TYPE                          OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__K_I_CTYPE                         float
#define OD_CURRENT_CONTROLLER__K_I_ACCESS                        OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__K_I_PDO                           0u
#define OD_CURRENT_CONTROLLER__K_I_DEFAULT                       0.0492f /* V/A */
#define OD_CURRENT_CONTROLLER__K_I_MIN                           0.0f /* V/A */
#define OD_CURRENT_CONTROLLER__K_I_MAX                           100.0f /* V/A */
#define OD_CURRENT_CONTROLLER__K_I_REF                           0x20100520UL
/* 0x2010:06 current_controller.T_BT REAL32 rw [s] - blanking time estimate (eq. 25) */
#define OD_CURRENT_CONTROLLER__T_BT_INDEX                        0x2010u
#define OD_CURRENT_CONTROLLER__T_BT_SUB                          0x06u
#define OD_CURRENT_CONTROLLER__T_BT_TYPE                         OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__T_BT_CTYPE                        float
#define OD_CURRENT_CONTROLLER__T_BT_ACCESS                       OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__T_BT_PDO                          0u
#define OD_CURRENT_CONTROLLER__T_BT_DEFAULT                      0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_BT_MIN                          0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_BT_MAX                          2e-05f /* s */
#define OD_CURRENT_CONTROLLER__T_BT_REF                          0x20100620UL
/* 0x2010:07 current_controller.T_DD REAL32 rw [s] - driver delay estimate (eq. 25) */
#define OD_CURRENT_CONTROLLER__T_DD_INDEX                        0x2010u
#define OD_CURRENT_CONTROLLER__T_DD_SUB                          0x07u
#define OD_CURRENT_CONTROLLER__T_DD_TYPE                         OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__T_DD_CTYPE                        float
#define OD_CURRENT_CONTROLLER__T_DD_ACCESS                       OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__T_DD_PDO                          0u
#define OD_CURRENT_CONTROLLER__T_DD_DEFAULT                      0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_DD_MIN                          0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_DD_MAX                          2e-05f /* s */
#define OD_CURRENT_CONTROLLER__T_DD_REF                          0x20100720UL
/* 0x2010:08 current_controller.T_SD REAL32 rw [s] - sampling delay estimate (eq. 25) */
#define OD_CURRENT_CONTROLLER__T_SD_INDEX                        0x2010u
#define OD_CURRENT_CONTROLLER__T_SD_SUB                          0x08u
#define OD_CURRENT_CONTROLLER__T_SD_TYPE                         OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__T_SD_CTYPE                        float
#define OD_CURRENT_CONTROLLER__T_SD_ACCESS                       OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__T_SD_PDO                          0u
#define OD_CURRENT_CONTROLLER__T_SD_DEFAULT                      0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_SD_MIN                          0.0f /* s */
#define OD_CURRENT_CONTROLLER__T_SD_MAX                          2e-05f /* s */
#define OD_CURRENT_CONTROLLER__T_SD_REF                          0x20100820UL
/* 0x2010:09 current_controller.V_G REAL32 rw [V] - switch voltage drop estimate (eq. 25) */
#define OD_CURRENT_CONTROLLER__V_G_INDEX                         0x2010u
#define OD_CURRENT_CONTROLLER__V_G_SUB                           0x09u
#define OD_CURRENT_CONTROLLER__V_G_TYPE                          OD_TYPE_REAL32
#define OD_CURRENT_CONTROLLER__V_G_CTYPE                         float
#define OD_CURRENT_CONTROLLER__V_G_ACCESS                        OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__V_G_PDO                           0u
#define OD_CURRENT_CONTROLLER__V_G_DEFAULT                       0.0f /* V */
#define OD_CURRENT_CONTROLLER__V_G_MIN                           0.0f /* V */
#define OD_CURRENT_CONTROLLER__V_G_MAX                           5.0f /* V */
#define OD_CURRENT_CONTROLLER__V_G_REF                           0x20100920UL
/* 0x2010:0A current_controller.emf_feedforward UNSIGNED8 rw [1] - 1 = add back-EMF feed-forward */
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_INDEX             0x2010u
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_SUB               0x0Au
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_TYPE              OD_TYPE_U8
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_CTYPE             uint16_t
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_ACCESS            OD_ACCESS_RW
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_PDO               0u
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_DEFAULT           0u /* 1 */
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_MIN               0u /* 1 */
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_MAX               1u /* 1 */
#define OD_CURRENT_CONTROLLER__EMF_FEEDFORWARD_REF               0x20100A08UL

/* ---- 0x2020 speed_controller ---- */
#define OD_SPEED_CONTROLLER_INDEX                                0x2020u
/* 0x2020:00 speed_controller.highest_sub_index UNSIGNED8 const */
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_INDEX             0x2020u
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_SUB               0x00u
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_TYPE              OD_TYPE_U8
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_CTYPE             uint16_t
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_ACCESS            OD_ACCESS_CONST
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_PDO               0u
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_DEFAULT           3u
#define OD_SPEED_CONTROLLER__HIGHEST_SUB_INDEX_REF               0x20200008UL
/* 0x2020:01 speed_controller.k_p REAL32 rw [A/rpm] - IP speed controller proportional gain (eq. 28-31) */
#define OD_SPEED_CONTROLLER__K_P_INDEX                           0x2020u
#define OD_SPEED_CONTROLLER__K_P_SUB                             0x01u
#define OD_SPEED_CONTROLLER__K_P_TYPE                            OD_TYPE_REAL32
#define OD_SPEED_CONTROLLER__K_P_CTYPE                           float
#define OD_SPEED_CONTROLLER__K_P_ACCESS                          OD_ACCESS_RW
#define OD_SPEED_CONTROLLER__K_P_PDO                             0u
#define OD_SPEED_CONTROLLER__K_P_DEFAULT                         0.2113f /* A/rpm */
#define OD_SPEED_CONTROLLER__K_P_MIN                             0.0f /* A/rpm */
#define OD_SPEED_CONTROLLER__K_P_MAX                             100.0f /* A/rpm */
#define OD_SPEED_CONTROLLER__K_P_REF                             0x20200120UL
/* 0x2020:02 speed_controller.k_i REAL32 rw [1/sample] - IP speed controller integral gain per 20 us sample */
#define OD_SPEED_CONTROLLER__K_I_INDEX                           0x2020u
#define OD_SPEED_CONTROLLER__K_I_SUB                             0x02u
#define OD_SPEED_CONTROLLER__K_I_TYPE                            OD_TYPE_REAL32
#define OD_SPEED_CONTROLLER__K_I_CTYPE                           float
#define OD_SPEED_CONTROLLER__K_I_ACCESS                          OD_ACCESS_RW
#define OD_SPEED_CONTROLLER__K_I_PDO                             0u
#define OD_SPEED_CONTROLLER__K_I_DEFAULT                         2.9994e-05f /* 1/sample */
#define OD_SPEED_CONTROLLER__K_I_MIN                             0.0f /* 1/sample */
#define OD_SPEED_CONTROLLER__K_I_MAX                             1.0f /* 1/sample */
#define OD_SPEED_CONTROLLER__K_I_REF                             0x20200220UL
/* 0x2020:03 speed_controller.current_limit REAL32 rw [A] - limit of the i_p reference */
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_INDEX                 0x2020u
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_SUB                   0x03u
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_TYPE                  OD_TYPE_REAL32
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_CTYPE                 float
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_ACCESS                OD_ACCESS_RW
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_PDO                   0u
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_DEFAULT               100.0f /* A */
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_MIN                   0.0f /* A */
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_MAX                   200.0f /* A */
#define OD_SPEED_CONTROLLER__CURRENT_LIMIT_REF                   0x20200320UL

/* ---- 0x2030 setpoints ---- */
#define OD_SETPOINTS_INDEX                                       0x2030u
/* 0x2030:00 setpoints.highest_sub_index UNSIGNED8 const */
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_INDEX                    0x2030u
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_SUB                      0x00u
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_TYPE                     OD_TYPE_U8
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_CTYPE                    uint16_t
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_ACCESS                   OD_ACCESS_CONST
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_PDO                      0u
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_DEFAULT                  1u
#define OD_SETPOINTS__HIGHEST_SUB_INDEX_REF                      0x20300008UL
/* 0x2030:01 setpoints.i_p_ref REAL32 rw [A] - pseudo-current reference in mode -1, |i_p_ref| <= speed_controller.current_limit */
#define OD_SETPOINTS__I_P_REF_INDEX                              0x2030u
#define OD_SETPOINTS__I_P_REF_SUB                                0x01u
#define OD_SETPOINTS__I_P_REF_TYPE                               OD_TYPE_REAL32
#define OD_SETPOINTS__I_P_REF_CTYPE                              float
#define OD_SETPOINTS__I_P_REF_ACCESS                             OD_ACCESS_RW
#define OD_SETPOINTS__I_P_REF_PDO                                1u
#define OD_SETPOINTS__I_P_REF_DEFAULT                            0.0f /* A */
#define OD_SETPOINTS__I_P_REF_MIN                                (-200.0f) /* A */
#define OD_SETPOINTS__I_P_REF_MAX                                200.0f /* A */
#define OD_SETPOINTS__I_P_REF_REF                                0x20300120UL

/* ---- 0x2040 measurements ---- */
#define OD_MEASUREMENTS_INDEX                                    0x2040u
/* 0x2040:00 measurements.highest_sub_index UNSIGNED8 const */
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_INDEX                 0x2040u
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_SUB                   0x00u
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_TYPE                  OD_TYPE_U8
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_CTYPE                 uint16_t
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_ACCESS                OD_ACCESS_CONST
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_PDO                   0u
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_DEFAULT               17u
#define OD_MEASUREMENTS__HIGHEST_SUB_INDEX_REF                   0x20400008UL
/* 0x2040:01 measurements.i_p REAL32 ro [A] - pseudo current (|i_a|+|i_b|+|i_c|)/2 with sign, limits are the measurement range */
#define OD_MEASUREMENTS__I_P_INDEX                               0x2040u
#define OD_MEASUREMENTS__I_P_SUB                                 0x01u
#define OD_MEASUREMENTS__I_P_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_P_CTYPE                               float
#define OD_MEASUREMENTS__I_P_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__I_P_PDO                                 1u
#define OD_MEASUREMENTS__I_P_DEFAULT                             0.0f /* A */
#define OD_MEASUREMENTS__I_P_MIN                                 (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_P_MAX                                 1000.0f /* A */
#define OD_MEASUREMENTS__I_P_REF                                 0x20400120UL
/* 0x2040:02 measurements.i_a REAL32 ro [A] - phase a current, limits are the measurement range */
#define OD_MEASUREMENTS__I_A_INDEX                               0x2040u
#define OD_MEASUREMENTS__I_A_SUB                                 0x02u
#define OD_MEASUREMENTS__I_A_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_A_CTYPE                               float
#define OD_MEASUREMENTS__I_A_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__I_A_PDO                                 1u
#define OD_MEASUREMENTS__I_A_DEFAULT                             0.0f /* A */
#define OD_MEASUREMENTS__I_A_MIN                                 (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_A_MAX                                 1000.0f /* A */
#define OD_MEASUREMENTS__I_A_REF                                 0x20400220UL
/* 0x2040:03 measurements.i_b REAL32 ro [A] - phase b current, limits are the measurement range */
#define OD_MEASUREMENTS__I_B_INDEX                               0x2040u
#define OD_MEASUREMENTS__I_B_SUB                                 0x03u
#define OD_MEASUREMENTS__I_B_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_B_CTYPE                               float
#define OD_MEASUREMENTS__I_B_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__I_B_PDO                                 1u
#define OD_MEASUREMENTS__I_B_DEFAULT                             0.0f /* A */
#define OD_MEASUREMENTS__I_B_MIN                                 (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_B_MAX                                 1000.0f /* A */
#define OD_MEASUREMENTS__I_B_REF                                 0x20400320UL
/* 0x2040:04 measurements.i_c REAL32 ro [A] - phase c current, limits are the measurement range */
#define OD_MEASUREMENTS__I_C_INDEX                               0x2040u
#define OD_MEASUREMENTS__I_C_SUB                                 0x04u
#define OD_MEASUREMENTS__I_C_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_C_CTYPE                               float
#define OD_MEASUREMENTS__I_C_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__I_C_PDO                                 1u
#define OD_MEASUREMENTS__I_C_DEFAULT                             0.0f /* A */
#define OD_MEASUREMENTS__I_C_MIN                                 (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_C_MAX                                 1000.0f /* A */
#define OD_MEASUREMENTS__I_C_REF                                 0x20400420UL
/* 0x2040:05 measurements.speed REAL32 ro [rpm] - mechanical speed, limits are the measurement range */
#define OD_MEASUREMENTS__SPEED_INDEX                             0x2040u
#define OD_MEASUREMENTS__SPEED_SUB                               0x05u
#define OD_MEASUREMENTS__SPEED_TYPE                              OD_TYPE_REAL32
#define OD_MEASUREMENTS__SPEED_CTYPE                             float
#define OD_MEASUREMENTS__SPEED_ACCESS                            OD_ACCESS_RO
#define OD_MEASUREMENTS__SPEED_PDO                               1u
#define OD_MEASUREMENTS__SPEED_DEFAULT                           0.0f /* rpm */
#define OD_MEASUREMENTS__SPEED_MIN                               (-20000.0f) /* rpm */
#define OD_MEASUREMENTS__SPEED_MAX                               20000.0f /* rpm */
#define OD_MEASUREMENTS__SPEED_REF                               0x20400520UL
/* 0x2040:06 measurements.v_L REAL32 ro [V] - line voltage applied to the conducting pair, limits are the measurement range */
#define OD_MEASUREMENTS__V_L_INDEX                               0x2040u
#define OD_MEASUREMENTS__V_L_SUB                                 0x06u
#define OD_MEASUREMENTS__V_L_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__V_L_CTYPE                               float
#define OD_MEASUREMENTS__V_L_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__V_L_PDO                                 1u
#define OD_MEASUREMENTS__V_L_DEFAULT                             0.0f /* V */
#define OD_MEASUREMENTS__V_L_MIN                                 (-200.0f) /* V */
#define OD_MEASUREMENTS__V_L_MAX                                 200.0f /* V */
#define OD_MEASUREMENTS__V_L_REF                                 0x20400620UL
/* 0x2040:07 measurements.e_L REAL32 ro [V] - line back-EMF of the conducting pair, limits are the measurement range */
#define OD_MEASUREMENTS__E_L_INDEX                               0x2040u
#define OD_MEASUREMENTS__E_L_SUB                                 0x07u
#define OD_MEASUREMENTS__E_L_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__E_L_CTYPE                               float
#define OD_MEASUREMENTS__E_L_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__E_L_PDO                                 1u
#define OD_MEASUREMENTS__E_L_DEFAULT                             0.0f /* V */
#define OD_MEASUREMENTS__E_L_MIN                                 (-200.0f) /* V */
#define OD_MEASUREMENTS__E_L_MAX                                 200.0f /* V */
#define OD_MEASUREMENTS__E_L_REF                                 0x20400720UL
/* 0x2040:08 measurements.m REAL32 ro [1] - modulation index, limits are the measurement range */
#define OD_MEASUREMENTS__M_INDEX                                 0x2040u
#define OD_MEASUREMENTS__M_SUB                                   0x08u
#define OD_MEASUREMENTS__M_TYPE                                  OD_TYPE_REAL32
#define OD_MEASUREMENTS__M_CTYPE                                 float
#define OD_MEASUREMENTS__M_ACCESS                                OD_ACCESS_RO
#define OD_MEASUREMENTS__M_PDO                                   1u
#define OD_MEASUREMENTS__M_DEFAULT                               0.0f /* 1 */
#define OD_MEASUREMENTS__M_MIN                                   (-1.0f) /* 1 */
#define OD_MEASUREMENTS__M_MAX                                   1.0f /* 1 */
#define OD_MEASUREMENTS__M_REF                                   0x20400820UL
/* 0x2040:09 measurements.hall_sector UNSIGNED8 ro [1] - Hall sector 1..6 */
#define OD_MEASUREMENTS__HALL_SECTOR_INDEX                       0x2040u
#define OD_MEASUREMENTS__HALL_SECTOR_SUB                         0x09u
#define OD_MEASUREMENTS__HALL_SECTOR_TYPE                        OD_TYPE_U8
#define OD_MEASUREMENTS__HALL_SECTOR_CTYPE                       uint16_t
#define OD_MEASUREMENTS__HALL_SECTOR_ACCESS                      OD_ACCESS_RO
#define OD_MEASUREMENTS__HALL_SECTOR_PDO                         1u
#define OD_MEASUREMENTS__HALL_SECTOR_DEFAULT                     1u /* 1 */
#define OD_MEASUREMENTS__HALL_SECTOR_MIN                         1u /* 1 */
#define OD_MEASUREMENTS__HALL_SECTOR_MAX                         6u /* 1 */
#define OD_MEASUREMENTS__HALL_SECTOR_REF                         0x20400908UL
/* 0x2040:0A measurements.i_p_ref REAL32 ro [A] - active pseudo-current reference, limits are the measurement range */
#define OD_MEASUREMENTS__I_P_REF_INDEX                           0x2040u
#define OD_MEASUREMENTS__I_P_REF_SUB                             0x0Au
#define OD_MEASUREMENTS__I_P_REF_TYPE                            OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_P_REF_CTYPE                           float
#define OD_MEASUREMENTS__I_P_REF_ACCESS                          OD_ACCESS_RO
#define OD_MEASUREMENTS__I_P_REF_PDO                             1u
#define OD_MEASUREMENTS__I_P_REF_DEFAULT                         0.0f /* A */
#define OD_MEASUREMENTS__I_P_REF_MIN                             (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_P_REF_MAX                             1000.0f /* A */
#define OD_MEASUREMENTS__I_P_REF_REF                             0x20400A20UL
/* 0x2040:0B measurements.speed_ref REAL32 ro [rpm] - active speed reference (after the ramp), limits are the measurement range */
#define OD_MEASUREMENTS__SPEED_REF_INDEX                         0x2040u
#define OD_MEASUREMENTS__SPEED_REF_SUB                           0x0Bu
#define OD_MEASUREMENTS__SPEED_REF_TYPE                          OD_TYPE_REAL32
#define OD_MEASUREMENTS__SPEED_REF_CTYPE                         float
#define OD_MEASUREMENTS__SPEED_REF_ACCESS                        OD_ACCESS_RO
#define OD_MEASUREMENTS__SPEED_REF_PDO                           1u
#define OD_MEASUREMENTS__SPEED_REF_DEFAULT                       0.0f /* rpm */
#define OD_MEASUREMENTS__SPEED_REF_MIN                           (-20000.0f) /* rpm */
#define OD_MEASUREMENTS__SPEED_REF_MAX                           20000.0f /* rpm */
#define OD_MEASUREMENTS__SPEED_REF_REF                           0x20400B20UL
/* 0x2040:0C measurements.V_dc REAL32 ro [V] - DC-link voltage, limits are the measurement range */
#define OD_MEASUREMENTS__V_DC_INDEX                              0x2040u
#define OD_MEASUREMENTS__V_DC_SUB                                0x0Cu
#define OD_MEASUREMENTS__V_DC_TYPE                               OD_TYPE_REAL32
#define OD_MEASUREMENTS__V_DC_CTYPE                              float
#define OD_MEASUREMENTS__V_DC_ACCESS                             OD_ACCESS_RO
#define OD_MEASUREMENTS__V_DC_PDO                                1u
#define OD_MEASUREMENTS__V_DC_DEFAULT                            0.0f /* V */
#define OD_MEASUREMENTS__V_DC_MIN                                0.0f /* V */
#define OD_MEASUREMENTS__V_DC_MAX                                200.0f /* V */
#define OD_MEASUREMENTS__V_DC_REF                                0x20400C20UL
/* 0x2040:0D measurements.T_e REAL32 ro [N*m] - electromagnetic torque, limits are the measurement range */
#define OD_MEASUREMENTS__T_E_INDEX                               0x2040u
#define OD_MEASUREMENTS__T_E_SUB                                 0x0Du
#define OD_MEASUREMENTS__T_E_TYPE                                OD_TYPE_REAL32
#define OD_MEASUREMENTS__T_E_CTYPE                               float
#define OD_MEASUREMENTS__T_E_ACCESS                              OD_ACCESS_RO
#define OD_MEASUREMENTS__T_E_PDO                                 1u
#define OD_MEASUREMENTS__T_E_DEFAULT                             0.0f /* N*m */
#define OD_MEASUREMENTS__T_E_MIN                                 (-100.0f) /* N*m */
#define OD_MEASUREMENTS__T_E_MAX                                 100.0f /* N*m */
#define OD_MEASUREMENTS__T_E_REF                                 0x20400D20UL
/* 0x2040:0E measurements.theta_e REAL32 ro [rad] - electrical angle, limits are the measurement range */
#define OD_MEASUREMENTS__THETA_E_INDEX                           0x2040u
#define OD_MEASUREMENTS__THETA_E_SUB                             0x0Eu
#define OD_MEASUREMENTS__THETA_E_TYPE                            OD_TYPE_REAL32
#define OD_MEASUREMENTS__THETA_E_CTYPE                           float
#define OD_MEASUREMENTS__THETA_E_ACCESS                          OD_ACCESS_RO
#define OD_MEASUREMENTS__THETA_E_PDO                             1u
#define OD_MEASUREMENTS__THETA_E_DEFAULT                         0.0f /* rad */
#define OD_MEASUREMENTS__THETA_E_MIN                             0.0f /* rad */
#define OD_MEASUREMENTS__THETA_E_MAX                             6.2831855f /* rad */
#define OD_MEASUREMENTS__THETA_E_REF                             0x20400E20UL
/* 0x2040:0F measurements.i_p_min REAL32 ro [A] - least pseudo current over the PWM period before the sample: the firmware converts i_p at every PWM switching edge (ADC start of conversion on each compare event) and at the period boundary and keeps the minimum (the current is monotonic between edges, so this is the ripple trough), limits are the measurement range */
#define OD_MEASUREMENTS__I_P_MIN_INDEX                           0x2040u
#define OD_MEASUREMENTS__I_P_MIN_SUB                             0x0Fu
#define OD_MEASUREMENTS__I_P_MIN_TYPE                            OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_P_MIN_CTYPE                           float
#define OD_MEASUREMENTS__I_P_MIN_ACCESS                          OD_ACCESS_RO
#define OD_MEASUREMENTS__I_P_MIN_PDO                             1u
#define OD_MEASUREMENTS__I_P_MIN_DEFAULT                         0.0f /* A */
#define OD_MEASUREMENTS__I_P_MIN_MIN                             (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_P_MIN_MAX                             1000.0f /* A */
#define OD_MEASUREMENTS__I_P_MIN_REF                             0x20400F20UL
/* 0x2040:10 measurements.i_p_max REAL32 ro [A] - largest pseudo current over the PWM period before the sample, from the same edge-triggered ADC conversions as i_p_min (the ripple peak; i_p_max - i_p_min is the ripple peak-to-peak), limits are the measurement range */
#define OD_MEASUREMENTS__I_P_MAX_INDEX                           0x2040u
#define OD_MEASUREMENTS__I_P_MAX_SUB                             0x10u
#define OD_MEASUREMENTS__I_P_MAX_TYPE                            OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_P_MAX_CTYPE                           float
#define OD_MEASUREMENTS__I_P_MAX_ACCESS                          OD_ACCESS_RO
#define OD_MEASUREMENTS__I_P_MAX_PDO                             1u
#define OD_MEASUREMENTS__I_P_MAX_DEFAULT                         0.0f /* A */
#define OD_MEASUREMENTS__I_P_MAX_MIN                             (-1000.0f) /* A */
#define OD_MEASUREMENTS__I_P_MAX_MAX                             1000.0f /* A */
#define OD_MEASUREMENTS__I_P_MAX_REF                             0x20401020UL
/* 0x2040:11 measurements.i_p_peaks REAL32 ro [1] - ripple cycles of i_p in the PWM period before the sample: local maxima (a rise then a fall) of the edge-triggered ADC conversions of i_p; the ripple frequency is i_p_peaks x f_s (2 for unipolar PWM) */
#define OD_MEASUREMENTS__I_P_PEAKS_INDEX                         0x2040u
#define OD_MEASUREMENTS__I_P_PEAKS_SUB                           0x11u
#define OD_MEASUREMENTS__I_P_PEAKS_TYPE                          OD_TYPE_REAL32
#define OD_MEASUREMENTS__I_P_PEAKS_CTYPE                         float
#define OD_MEASUREMENTS__I_P_PEAKS_ACCESS                        OD_ACCESS_RO
#define OD_MEASUREMENTS__I_P_PEAKS_PDO                           1u
#define OD_MEASUREMENTS__I_P_PEAKS_DEFAULT                       0.0f /* 1 */
#define OD_MEASUREMENTS__I_P_PEAKS_MIN                           0.0f /* 1 */
#define OD_MEASUREMENTS__I_P_PEAKS_MAX                           16.0f /* 1 */
#define OD_MEASUREMENTS__I_P_PEAKS_REF                           0x20401120UL

/* ---- 0x2050 protection ---- */
#define OD_PROTECTION_INDEX                                      0x2050u
/* 0x2050:00 protection.highest_sub_index UNSIGNED8 const */
#define OD_PROTECTION__HIGHEST_SUB_INDEX_INDEX                   0x2050u
#define OD_PROTECTION__HIGHEST_SUB_INDEX_SUB                     0x00u
#define OD_PROTECTION__HIGHEST_SUB_INDEX_TYPE                    OD_TYPE_U8
#define OD_PROTECTION__HIGHEST_SUB_INDEX_CTYPE                   uint16_t
#define OD_PROTECTION__HIGHEST_SUB_INDEX_ACCESS                  OD_ACCESS_CONST
#define OD_PROTECTION__HIGHEST_SUB_INDEX_PDO                     0u
#define OD_PROTECTION__HIGHEST_SUB_INDEX_DEFAULT                 3u
#define OD_PROTECTION__HIGHEST_SUB_INDEX_REF                     0x20500008UL
/* 0x2050:01 protection.overcurrent_trip REAL32 rw [A] - instantaneous phase overcurrent trip (EMCY 0x2310) */
#define OD_PROTECTION__OVERCURRENT_TRIP_INDEX                    0x2050u
#define OD_PROTECTION__OVERCURRENT_TRIP_SUB                      0x01u
#define OD_PROTECTION__OVERCURRENT_TRIP_TYPE                     OD_TYPE_REAL32
#define OD_PROTECTION__OVERCURRENT_TRIP_CTYPE                    float
#define OD_PROTECTION__OVERCURRENT_TRIP_ACCESS                   OD_ACCESS_RW
#define OD_PROTECTION__OVERCURRENT_TRIP_PDO                      0u
#define OD_PROTECTION__OVERCURRENT_TRIP_DEFAULT                  300.0f /* A */
#define OD_PROTECTION__OVERCURRENT_TRIP_MIN                      1.0f /* A */
#define OD_PROTECTION__OVERCURRENT_TRIP_MAX                      1000.0f /* A */
#define OD_PROTECTION__OVERCURRENT_TRIP_CONFIG_ONLY              1u /* write only with the power stage off, else 0x08000022 */
#define OD_PROTECTION__OVERCURRENT_TRIP_REF                      0x20500120UL
/* 0x2050:02 protection.overvoltage_trip REAL32 rw [V] - DC-link overvoltage trip (EMCY 0x3210) */
#define OD_PROTECTION__OVERVOLTAGE_TRIP_INDEX                    0x2050u
#define OD_PROTECTION__OVERVOLTAGE_TRIP_SUB                      0x02u
#define OD_PROTECTION__OVERVOLTAGE_TRIP_TYPE                     OD_TYPE_REAL32
#define OD_PROTECTION__OVERVOLTAGE_TRIP_CTYPE                    float
#define OD_PROTECTION__OVERVOLTAGE_TRIP_ACCESS                   OD_ACCESS_RW
#define OD_PROTECTION__OVERVOLTAGE_TRIP_PDO                      0u
#define OD_PROTECTION__OVERVOLTAGE_TRIP_DEFAULT                  60.0f /* V */
#define OD_PROTECTION__OVERVOLTAGE_TRIP_MIN                      1.0f /* V */
#define OD_PROTECTION__OVERVOLTAGE_TRIP_MAX                      100.0f /* V */
#define OD_PROTECTION__OVERVOLTAGE_TRIP_CONFIG_ONLY              1u /* write only with the power stage off, else 0x08000022 */
#define OD_PROTECTION__OVERVOLTAGE_TRIP_REF                      0x20500220UL
/* 0x2050:03 protection.undervoltage_trip REAL32 rw [V] - DC-link undervoltage trip (EMCY 0x3220) */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_INDEX                   0x2050u
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_SUB                     0x03u
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_TYPE                    OD_TYPE_REAL32
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_CTYPE                   float
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_ACCESS                  OD_ACCESS_RW
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_PDO                     0u
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_DEFAULT                 36.0f /* V */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_MIN                     0.0f /* V */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_MAX                     100.0f /* V */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_CONFIG_ONLY             1u /* write only with the power stage off, else 0x08000022 */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_REF                     0x20500320UL

/* ---- 0x2060 store_status ---- */
/* 0x2060:00 store_status UNSIGNED8 ro [1] - parameter store at the last boot / reset node: 0 stored parameters loaded, 1 defaults (no store file or restored defaults), 2 damaged file (checksum/parse failed, defaults used), 3 unreadable (I/O error, defaults used); 2/3 also send EMCY 0x6310 after the boot-up */
#define OD_STORE_STATUS_INDEX                                    0x2060u
#define OD_STORE_STATUS_SUB                                      0x00u
#define OD_STORE_STATUS_TYPE                                     OD_TYPE_U8
#define OD_STORE_STATUS_CTYPE                                    uint16_t
#define OD_STORE_STATUS_ACCESS                                   OD_ACCESS_RO
#define OD_STORE_STATUS_PDO                                      0u
#define OD_STORE_STATUS_DEFAULT                                  1u /* 1 */
#define OD_STORE_STATUS_MIN                                      0u /* 1 */
#define OD_STORE_STATUS_MAX                                      3u /* 1 */
#define OD_STORE_STATUS_REF                                      0x20600008UL
#define OD_STORE_STATUS_OK                                       0u
#define OD_STORE_STATUS_DEFAULTS                                 1u
#define OD_STORE_STATUS_DAMAGED                                  2u
#define OD_STORE_STATUS_UNREADABLE                               3u

/* ---- 0x2070 tpdo_missed_events ---- */
#define OD_TPDO_MISSED_EVENTS_INDEX                              0x2070u
/* 0x2070:00 tpdo_missed_events.highest_sub_index UNSIGNED8 const */
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_INDEX           0x2070u
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_SUB             0x00u
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_TYPE            OD_TYPE_U8
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_CTYPE           uint16_t
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_ACCESS          OD_ACCESS_CONST
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_PDO             0u
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_DEFAULT         4u
#define OD_TPDO_MISSED_EVENTS__HIGHEST_SUB_INDEX_REF             0x20700008UL
/* 0x2070:01 tpdo_missed_events.tpdo1 UNSIGNED32 ro [1] - event-timer periods of TPDO1 that passed without a frame (the drive was late or stalled; no burst is sent to catch up), since power-on or reset communication, wraps at 2^32 */
#define OD_TPDO_MISSED_EVENTS__TPDO1_INDEX                       0x2070u
#define OD_TPDO_MISSED_EVENTS__TPDO1_SUB                         0x01u
#define OD_TPDO_MISSED_EVENTS__TPDO1_TYPE                        OD_TYPE_U32
#define OD_TPDO_MISSED_EVENTS__TPDO1_CTYPE                       uint32_t
#define OD_TPDO_MISSED_EVENTS__TPDO1_ACCESS                      OD_ACCESS_RO
#define OD_TPDO_MISSED_EVENTS__TPDO1_PDO                         0u
#define OD_TPDO_MISSED_EVENTS__TPDO1_DEFAULT                     0x00000000UL /* 1 */
#define OD_TPDO_MISSED_EVENTS__TPDO1_REF                         0x20700120UL
/* 0x2070:02 tpdo_missed_events.tpdo2 UNSIGNED32 ro [1] - event-timer periods of TPDO2 that passed without a frame (the drive was late or stalled; no burst is sent to catch up), since power-on or reset communication, wraps at 2^32 */
#define OD_TPDO_MISSED_EVENTS__TPDO2_INDEX                       0x2070u
#define OD_TPDO_MISSED_EVENTS__TPDO2_SUB                         0x02u
#define OD_TPDO_MISSED_EVENTS__TPDO2_TYPE                        OD_TYPE_U32
#define OD_TPDO_MISSED_EVENTS__TPDO2_CTYPE                       uint32_t
#define OD_TPDO_MISSED_EVENTS__TPDO2_ACCESS                      OD_ACCESS_RO
#define OD_TPDO_MISSED_EVENTS__TPDO2_PDO                         0u
#define OD_TPDO_MISSED_EVENTS__TPDO2_DEFAULT                     0x00000000UL /* 1 */
#define OD_TPDO_MISSED_EVENTS__TPDO2_REF                         0x20700220UL
/* 0x2070:03 tpdo_missed_events.tpdo3 UNSIGNED32 ro [1] - event-timer periods of TPDO3 that passed without a frame (the drive was late or stalled; no burst is sent to catch up), since power-on or reset communication, wraps at 2^32 */
#define OD_TPDO_MISSED_EVENTS__TPDO3_INDEX                       0x2070u
#define OD_TPDO_MISSED_EVENTS__TPDO3_SUB                         0x03u
#define OD_TPDO_MISSED_EVENTS__TPDO3_TYPE                        OD_TYPE_U32
#define OD_TPDO_MISSED_EVENTS__TPDO3_CTYPE                       uint32_t
#define OD_TPDO_MISSED_EVENTS__TPDO3_ACCESS                      OD_ACCESS_RO
#define OD_TPDO_MISSED_EVENTS__TPDO3_PDO                         0u
#define OD_TPDO_MISSED_EVENTS__TPDO3_DEFAULT                     0x00000000UL /* 1 */
#define OD_TPDO_MISSED_EVENTS__TPDO3_REF                         0x20700320UL
/* 0x2070:04 tpdo_missed_events.tpdo4 UNSIGNED32 ro [1] - event-timer periods of TPDO4 that passed without a frame (the drive was late or stalled; no burst is sent to catch up), since power-on or reset communication, wraps at 2^32 */
#define OD_TPDO_MISSED_EVENTS__TPDO4_INDEX                       0x2070u
#define OD_TPDO_MISSED_EVENTS__TPDO4_SUB                         0x04u
#define OD_TPDO_MISSED_EVENTS__TPDO4_TYPE                        OD_TYPE_U32
#define OD_TPDO_MISSED_EVENTS__TPDO4_CTYPE                       uint32_t
#define OD_TPDO_MISSED_EVENTS__TPDO4_ACCESS                      OD_ACCESS_RO
#define OD_TPDO_MISSED_EVENTS__TPDO4_PDO                         0u
#define OD_TPDO_MISSED_EVENTS__TPDO4_DEFAULT                     0x00000000UL /* 1 */
#define OD_TPDO_MISSED_EVENTS__TPDO4_REF                         0x20700420UL

/* ---- 0x20F0 gain_set ---- */
#define OD_GAIN_SET_INDEX                                        0x20F0u
/* 0x20F0:00 gain_set.highest_sub_index UNSIGNED8 const */
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_INDEX                     0x20F0u
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_SUB                       0x00u
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_TYPE                      OD_TYPE_U8
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_CTYPE                     uint16_t
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_ACCESS                    OD_ACCESS_CONST
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_PDO                       0u
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_DEFAULT                   13u
#define OD_GAIN_SET__HIGHEST_SUB_INDEX_REF                       0x20F00008UL
/* 0x20F0:01 gain_set.type UNSIGNED8 rw [1] - staged copy of current_controller.type */
#define OD_GAIN_SET__TYPE_INDEX                                  0x20F0u
#define OD_GAIN_SET__TYPE_SUB                                    0x01u
#define OD_GAIN_SET__TYPE_TYPE                                   OD_TYPE_U8
#define OD_GAIN_SET__TYPE_CTYPE                                  uint16_t
#define OD_GAIN_SET__TYPE_ACCESS                                 OD_ACCESS_RW
#define OD_GAIN_SET__TYPE_PDO                                    0u
#define OD_GAIN_SET__TYPE_DEFAULT                                0u /* 1 */
#define OD_GAIN_SET__TYPE_MIN                                    0u /* 1 */
#define OD_GAIN_SET__TYPE_MAX                                    2u /* 1 */
#define OD_GAIN_SET__TYPE_REF                                    0x20F00108UL
#define OD_GAIN_SET__TYPE_DEADBEAT                               0u
#define OD_GAIN_SET__TYPE_PI                                     1u
#define OD_GAIN_SET__TYPE_PREDICTIVE                             2u
/* 0x20F0:02 gain_set.L_c REAL32 rw [H] - staged copy of current_controller.L_c */
#define OD_GAIN_SET__L_C_INDEX                                   0x20F0u
#define OD_GAIN_SET__L_C_SUB                                     0x02u
#define OD_GAIN_SET__L_C_TYPE                                    OD_TYPE_REAL32
#define OD_GAIN_SET__L_C_CTYPE                                   float
#define OD_GAIN_SET__L_C_ACCESS                                  OD_ACCESS_RW
#define OD_GAIN_SET__L_C_PDO                                     0u
#define OD_GAIN_SET__L_C_DEFAULT                                 1.48e-05f /* H */
#define OD_GAIN_SET__L_C_MIN                                     1e-08f /* H */
#define OD_GAIN_SET__L_C_MAX                                     0.002f /* H */
#define OD_GAIN_SET__L_C_REF                                     0x20F00220UL
/* 0x20F0:03 gain_set.R_c REAL32 rw [Ohm] - staged copy of current_controller.R_c */
#define OD_GAIN_SET__R_C_INDEX                                   0x20F0u
#define OD_GAIN_SET__R_C_SUB                                     0x03u
#define OD_GAIN_SET__R_C_TYPE                                    OD_TYPE_REAL32
#define OD_GAIN_SET__R_C_CTYPE                                   float
#define OD_GAIN_SET__R_C_ACCESS                                  OD_ACCESS_RW
#define OD_GAIN_SET__R_C_PDO                                     0u
#define OD_GAIN_SET__R_C_DEFAULT                                 0.0062f /* Ohm */
#define OD_GAIN_SET__R_C_MIN                                     0.0f /* Ohm */
#define OD_GAIN_SET__R_C_MAX                                     1.0f /* Ohm */
#define OD_GAIN_SET__R_C_MIN_NONZERO                             0.0001f /* Ohm: 0 or >= this */
#define OD_GAIN_SET__R_C_REF                                     0x20F00320UL
/* 0x20F0:04 gain_set.k_p REAL32 rw [V/A] - staged copy of current_controller.k_p */
#define OD_GAIN_SET__K_P_INDEX                                   0x20F0u
#define OD_GAIN_SET__K_P_SUB                                     0x04u
#define OD_GAIN_SET__K_P_TYPE                                    OD_TYPE_REAL32
#define OD_GAIN_SET__K_P_CTYPE                                   float
#define OD_GAIN_SET__K_P_ACCESS                                  OD_ACCESS_RW
#define OD_GAIN_SET__K_P_PDO                                     0u
#define OD_GAIN_SET__K_P_DEFAULT                                 0.4647f /* V/A */
#define OD_GAIN_SET__K_P_MIN                                     0.0f /* V/A */
#define OD_GAIN_SET__K_P_MAX                                     100.0f /* V/A */
#define OD_GAIN_SET__K_P_REF                                     0x20F00420UL
/* 0x20F0:05 gain_set.k_i REAL32 rw [V/A] - staged copy of current_controller.k_i */
#define OD_GAIN_SET__K_I_INDEX                                   0x20F0u
#define OD_GAIN_SET__K_I_SUB                                     0x05u
#define OD_GAIN_SET__K_I_TYPE                                    OD_TYPE_REAL32
#define OD_GAIN_SET__K_I_CTYPE                                   float
#define OD_GAIN_SET__K_I_ACCESS                                  OD_ACCESS_RW
#define OD_GAIN_SET__K_I_PDO                                     0u
#define OD_GAIN_SET__K_I_DEFAULT                                 0.0492f /* V/A */
#define OD_GAIN_SET__K_I_MIN                                     0.0f /* V/A */
#define OD_GAIN_SET__K_I_MAX                                     100.0f /* V/A */
#define OD_GAIN_SET__K_I_REF                                     0x20F00520UL
/* 0x20F0:06 gain_set.T_BT REAL32 rw [s] - staged copy of current_controller.T_BT */
#define OD_GAIN_SET__T_BT_INDEX                                  0x20F0u
#define OD_GAIN_SET__T_BT_SUB                                    0x06u
#define OD_GAIN_SET__T_BT_TYPE                                   OD_TYPE_REAL32
#define OD_GAIN_SET__T_BT_CTYPE                                  float
#define OD_GAIN_SET__T_BT_ACCESS                                 OD_ACCESS_RW
#define OD_GAIN_SET__T_BT_PDO                                    0u
#define OD_GAIN_SET__T_BT_DEFAULT                                0.0f /* s */
#define OD_GAIN_SET__T_BT_MIN                                    0.0f /* s */
#define OD_GAIN_SET__T_BT_MAX                                    2e-05f /* s */
#define OD_GAIN_SET__T_BT_REF                                    0x20F00620UL
/* 0x20F0:07 gain_set.T_DD REAL32 rw [s] - staged copy of current_controller.T_DD */
#define OD_GAIN_SET__T_DD_INDEX                                  0x20F0u
#define OD_GAIN_SET__T_DD_SUB                                    0x07u
#define OD_GAIN_SET__T_DD_TYPE                                   OD_TYPE_REAL32
#define OD_GAIN_SET__T_DD_CTYPE                                  float
#define OD_GAIN_SET__T_DD_ACCESS                                 OD_ACCESS_RW
#define OD_GAIN_SET__T_DD_PDO                                    0u
#define OD_GAIN_SET__T_DD_DEFAULT                                0.0f /* s */
#define OD_GAIN_SET__T_DD_MIN                                    0.0f /* s */
#define OD_GAIN_SET__T_DD_MAX                                    2e-05f /* s */
#define OD_GAIN_SET__T_DD_REF                                    0x20F00720UL
/* 0x20F0:08 gain_set.T_SD REAL32 rw [s] - staged copy of current_controller.T_SD */
#define OD_GAIN_SET__T_SD_INDEX                                  0x20F0u
#define OD_GAIN_SET__T_SD_SUB                                    0x08u
#define OD_GAIN_SET__T_SD_TYPE                                   OD_TYPE_REAL32
#define OD_GAIN_SET__T_SD_CTYPE                                  float
#define OD_GAIN_SET__T_SD_ACCESS                                 OD_ACCESS_RW
#define OD_GAIN_SET__T_SD_PDO                                    0u
#define OD_GAIN_SET__T_SD_DEFAULT                                0.0f /* s */
#define OD_GAIN_SET__T_SD_MIN                                    0.0f /* s */
#define OD_GAIN_SET__T_SD_MAX                                    2e-05f /* s */
#define OD_GAIN_SET__T_SD_REF                                    0x20F00820UL
/* 0x20F0:09 gain_set.V_G REAL32 rw [V] - staged copy of current_controller.V_G */
#define OD_GAIN_SET__V_G_INDEX                                   0x20F0u
#define OD_GAIN_SET__V_G_SUB                                     0x09u
#define OD_GAIN_SET__V_G_TYPE                                    OD_TYPE_REAL32
#define OD_GAIN_SET__V_G_CTYPE                                   float
#define OD_GAIN_SET__V_G_ACCESS                                  OD_ACCESS_RW
#define OD_GAIN_SET__V_G_PDO                                     0u
#define OD_GAIN_SET__V_G_DEFAULT                                 0.0f /* V */
#define OD_GAIN_SET__V_G_MIN                                     0.0f /* V */
#define OD_GAIN_SET__V_G_MAX                                     5.0f /* V */
#define OD_GAIN_SET__V_G_REF                                     0x20F00920UL
/* 0x20F0:0A gain_set.emf_feedforward UNSIGNED8 rw [1] - staged copy of current_controller.emf_feedforward */
#define OD_GAIN_SET__EMF_FEEDFORWARD_INDEX                       0x20F0u
#define OD_GAIN_SET__EMF_FEEDFORWARD_SUB                         0x0Au
#define OD_GAIN_SET__EMF_FEEDFORWARD_TYPE                        OD_TYPE_U8
#define OD_GAIN_SET__EMF_FEEDFORWARD_CTYPE                       uint16_t
#define OD_GAIN_SET__EMF_FEEDFORWARD_ACCESS                      OD_ACCESS_RW
#define OD_GAIN_SET__EMF_FEEDFORWARD_PDO                         0u
#define OD_GAIN_SET__EMF_FEEDFORWARD_DEFAULT                     0u /* 1 */
#define OD_GAIN_SET__EMF_FEEDFORWARD_MIN                         0u /* 1 */
#define OD_GAIN_SET__EMF_FEEDFORWARD_MAX                         1u /* 1 */
#define OD_GAIN_SET__EMF_FEEDFORWARD_REF                         0x20F00A08UL
/* 0x20F0:0B gain_set.speed_k_p REAL32 rw [A/rpm] - staged copy of speed_controller.k_p */
#define OD_GAIN_SET__SPEED_K_P_INDEX                             0x20F0u
#define OD_GAIN_SET__SPEED_K_P_SUB                               0x0Bu
#define OD_GAIN_SET__SPEED_K_P_TYPE                              OD_TYPE_REAL32
#define OD_GAIN_SET__SPEED_K_P_CTYPE                             float
#define OD_GAIN_SET__SPEED_K_P_ACCESS                            OD_ACCESS_RW
#define OD_GAIN_SET__SPEED_K_P_PDO                               0u
#define OD_GAIN_SET__SPEED_K_P_DEFAULT                           0.2113f /* A/rpm */
#define OD_GAIN_SET__SPEED_K_P_MIN                               0.0f /* A/rpm */
#define OD_GAIN_SET__SPEED_K_P_MAX                               100.0f /* A/rpm */
#define OD_GAIN_SET__SPEED_K_P_REF                               0x20F00B20UL
/* 0x20F0:0C gain_set.speed_k_i REAL32 rw [1/sample] - staged copy of speed_controller.k_i */
#define OD_GAIN_SET__SPEED_K_I_INDEX                             0x20F0u
#define OD_GAIN_SET__SPEED_K_I_SUB                               0x0Cu
#define OD_GAIN_SET__SPEED_K_I_TYPE                              OD_TYPE_REAL32
#define OD_GAIN_SET__SPEED_K_I_CTYPE                             float
#define OD_GAIN_SET__SPEED_K_I_ACCESS                            OD_ACCESS_RW
#define OD_GAIN_SET__SPEED_K_I_PDO                               0u
#define OD_GAIN_SET__SPEED_K_I_DEFAULT                           2.9994e-05f /* 1/sample */
#define OD_GAIN_SET__SPEED_K_I_MIN                               0.0f /* 1/sample */
#define OD_GAIN_SET__SPEED_K_I_MAX                               1.0f /* 1/sample */
#define OD_GAIN_SET__SPEED_K_I_REF                               0x20F00C20UL
/* 0x20F0:0D gain_set.speed_current_limit REAL32 rw [A] - staged copy of speed_controller.current_limit */
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_INDEX                   0x20F0u
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_SUB                     0x0Du
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_TYPE                    OD_TYPE_REAL32
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_CTYPE                   float
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_ACCESS                  OD_ACCESS_RW
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_PDO                     0u
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_DEFAULT                 100.0f /* A */
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_MIN                     0.0f /* A */
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_MAX                     200.0f /* A */
#define OD_GAIN_SET__SPEED_CURRENT_LIMIT_REF                     0x20F00D20UL

/* ---- 0x20F1 gain_set_apply ---- */
/* 0x20F1:00 gain_set_apply UNSIGNED8 wo [1] - 1 = apply gain_set 1..10, 2 = apply 11..13, 3 = both, validated as a whole and applied at one sample boundary or aborted with nothing changed */
#define OD_GAIN_SET_APPLY_INDEX                                  0x20F1u
#define OD_GAIN_SET_APPLY_SUB                                    0x00u
#define OD_GAIN_SET_APPLY_TYPE                                   OD_TYPE_U8
#define OD_GAIN_SET_APPLY_CTYPE                                  uint16_t
#define OD_GAIN_SET_APPLY_ACCESS                                 OD_ACCESS_WO
#define OD_GAIN_SET_APPLY_PDO                                    0u
#define OD_GAIN_SET_APPLY_DEFAULT                                0u /* 1 */
#define OD_GAIN_SET_APPLY_MIN                                    0u /* 1 */
#define OD_GAIN_SET_APPLY_MAX                                    3u /* 1 */
#define OD_GAIN_SET_APPLY_REF                                    0x20F10008UL
#define OD_GAIN_SET_APPLY_CURRENT                                1u
#define OD_GAIN_SET_APPLY_SPEED                                  2u
#define OD_GAIN_SET_APPLY_BOTH                                   3u

/* ---- 0x2100 trace_config ---- */
#define OD_TRACE_CONFIG_INDEX                                    0x2100u
/* 0x2100:00 trace_config.highest_sub_index UNSIGNED8 const */
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_INDEX                 0x2100u
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_SUB                   0x00u
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_TYPE                  OD_TYPE_U8
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_CTYPE                 uint16_t
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_ACCESS                OD_ACCESS_CONST
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_PDO                   0u
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_DEFAULT               13u
#define OD_TRACE_CONFIG__HIGHEST_SUB_INDEX_REF                   0x21000008UL
/* 0x2100:01 trace_config.channel_count UNSIGNED8 rw [1] */
#define OD_TRACE_CONFIG__CHANNEL_COUNT_INDEX                     0x2100u
#define OD_TRACE_CONFIG__CHANNEL_COUNT_SUB                       0x01u
#define OD_TRACE_CONFIG__CHANNEL_COUNT_TYPE                      OD_TYPE_U8
#define OD_TRACE_CONFIG__CHANNEL_COUNT_CTYPE                     uint16_t
#define OD_TRACE_CONFIG__CHANNEL_COUNT_ACCESS                    OD_ACCESS_RW
#define OD_TRACE_CONFIG__CHANNEL_COUNT_PDO                       0u
#define OD_TRACE_CONFIG__CHANNEL_COUNT_DEFAULT                   2u /* 1 */
#define OD_TRACE_CONFIG__CHANNEL_COUNT_MIN                       1u /* 1 */
#define OD_TRACE_CONFIG__CHANNEL_COUNT_MAX                       8u /* 1 */
#define OD_TRACE_CONFIG__CHANNEL_COUNT_REF                       0x21000108UL
/* 0x2100:02 trace_config.divider UNSIGNED16 rw [samples] - loop samples (20 us) per trace sample */
#define OD_TRACE_CONFIG__DIVIDER_INDEX                           0x2100u
#define OD_TRACE_CONFIG__DIVIDER_SUB                             0x02u
#define OD_TRACE_CONFIG__DIVIDER_TYPE                            OD_TYPE_U16
#define OD_TRACE_CONFIG__DIVIDER_CTYPE                           uint16_t
#define OD_TRACE_CONFIG__DIVIDER_ACCESS                          OD_ACCESS_RW
#define OD_TRACE_CONFIG__DIVIDER_PDO                             0u
#define OD_TRACE_CONFIG__DIVIDER_DEFAULT                         1u /* samples */
#define OD_TRACE_CONFIG__DIVIDER_MIN                             1u /* samples */
#define OD_TRACE_CONFIG__DIVIDER_MAX                             5000u /* samples */
#define OD_TRACE_CONFIG__DIVIDER_REF                             0x21000210UL
/* 0x2100:03 trace_config.length UNSIGNED16 rw [samples] - samples per channel, length * channel_count <= capacity */
#define OD_TRACE_CONFIG__LENGTH_INDEX                            0x2100u
#define OD_TRACE_CONFIG__LENGTH_SUB                              0x03u
#define OD_TRACE_CONFIG__LENGTH_TYPE                             OD_TYPE_U16
#define OD_TRACE_CONFIG__LENGTH_CTYPE                            uint16_t
#define OD_TRACE_CONFIG__LENGTH_ACCESS                           OD_ACCESS_RW
#define OD_TRACE_CONFIG__LENGTH_PDO                              0u
#define OD_TRACE_CONFIG__LENGTH_DEFAULT                          1000u /* samples */
#define OD_TRACE_CONFIG__LENGTH_MIN                              1u /* samples */
#define OD_TRACE_CONFIG__LENGTH_MAX                              16384u /* samples */
#define OD_TRACE_CONFIG__LENGTH_REF                              0x21000310UL
/* 0x2100:04 trace_config.pre_trigger UNSIGNED16 rw [samples] - samples kept before the trigger, < length */
#define OD_TRACE_CONFIG__PRE_TRIGGER_INDEX                       0x2100u
#define OD_TRACE_CONFIG__PRE_TRIGGER_SUB                         0x04u
#define OD_TRACE_CONFIG__PRE_TRIGGER_TYPE                        OD_TYPE_U16
#define OD_TRACE_CONFIG__PRE_TRIGGER_CTYPE                       uint16_t
#define OD_TRACE_CONFIG__PRE_TRIGGER_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CONFIG__PRE_TRIGGER_PDO                         0u
#define OD_TRACE_CONFIG__PRE_TRIGGER_DEFAULT                     100u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_MIN                         0u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_MAX                         16383u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_REF                         0x21000410UL
/* 0x2100:05 trace_config.trigger_source UNSIGNED32 rw - OD reference index<<16 | sub<<8 | 0x20 of a REAL32 */
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_INDEX                    0x2100u
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_SUB                      0x05u
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_TYPE                     OD_TYPE_U32
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_CTYPE                    uint32_t
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_ACCESS                   OD_ACCESS_RW
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_PDO                      0u
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_DEFAULT                  0x20400120UL
#define OD_TRACE_CONFIG__TRIGGER_SOURCE_REF                      0x21000520UL
/* 0x2100:06 trace_config.trigger_level REAL32 rw [unit of trigger_source] */
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_INDEX                     0x2100u
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_SUB                       0x06u
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_TYPE                      OD_TYPE_REAL32
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_CTYPE                     float
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_ACCESS                    OD_ACCESS_RW
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_PDO                       0u
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_DEFAULT                   0.0f /* unit of trigger_source */
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_MIN                       (-1000000.0f) /* unit of trigger_source */
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_MAX                       1000000.0f /* unit of trigger_source */
#define OD_TRACE_CONFIG__TRIGGER_LEVEL_REF                       0x21000620UL
/* 0x2100:07 trace_config.trigger_edge UNSIGNED8 rw [1] */
#define OD_TRACE_CONFIG__TRIGGER_EDGE_INDEX                      0x2100u
#define OD_TRACE_CONFIG__TRIGGER_EDGE_SUB                        0x07u
#define OD_TRACE_CONFIG__TRIGGER_EDGE_TYPE                       OD_TYPE_U8
#define OD_TRACE_CONFIG__TRIGGER_EDGE_CTYPE                      uint16_t
#define OD_TRACE_CONFIG__TRIGGER_EDGE_ACCESS                     OD_ACCESS_RW
#define OD_TRACE_CONFIG__TRIGGER_EDGE_PDO                        0u
#define OD_TRACE_CONFIG__TRIGGER_EDGE_DEFAULT                    0u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_EDGE_MIN                        0u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_EDGE_MAX                        2u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_EDGE_REF                        0x21000708UL
#define OD_TRACE_CONFIG__TRIGGER_EDGE_RISING                     0u
#define OD_TRACE_CONFIG__TRIGGER_EDGE_FALLING                    1u
#define OD_TRACE_CONFIG__TRIGGER_EDGE_EITHER                     2u
/* 0x2100:08 trace_config.trigger_mode UNSIGNED8 rw [1] - 0 immediate on arm, 1 signal crossing, 2 on setpoint step, 3 on fault */
#define OD_TRACE_CONFIG__TRIGGER_MODE_INDEX                      0x2100u
#define OD_TRACE_CONFIG__TRIGGER_MODE_SUB                        0x08u
#define OD_TRACE_CONFIG__TRIGGER_MODE_TYPE                       OD_TYPE_U8
#define OD_TRACE_CONFIG__TRIGGER_MODE_CTYPE                      uint16_t
#define OD_TRACE_CONFIG__TRIGGER_MODE_ACCESS                     OD_ACCESS_RW
#define OD_TRACE_CONFIG__TRIGGER_MODE_PDO                        0u
#define OD_TRACE_CONFIG__TRIGGER_MODE_DEFAULT                    0u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_MODE_MIN                        0u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_MODE_MAX                        3u /* 1 */
#define OD_TRACE_CONFIG__TRIGGER_MODE_REF                        0x21000808UL
#define OD_TRACE_CONFIG__TRIGGER_MODE_IMMEDIATE                  0u
#define OD_TRACE_CONFIG__TRIGGER_MODE_SIGNAL                     1u
#define OD_TRACE_CONFIG__TRIGGER_MODE_SETPOINT_STEP              2u
#define OD_TRACE_CONFIG__TRIGGER_MODE_FAULT                      3u
/* 0x2100:09 trace_config.command UNSIGNED8 rw [1] */
#define OD_TRACE_CONFIG__COMMAND_INDEX                           0x2100u
#define OD_TRACE_CONFIG__COMMAND_SUB                             0x09u
#define OD_TRACE_CONFIG__COMMAND_TYPE                            OD_TYPE_U8
#define OD_TRACE_CONFIG__COMMAND_CTYPE                           uint16_t
#define OD_TRACE_CONFIG__COMMAND_ACCESS                          OD_ACCESS_RW
#define OD_TRACE_CONFIG__COMMAND_PDO                             0u
#define OD_TRACE_CONFIG__COMMAND_DEFAULT                         0u /* 1 */
#define OD_TRACE_CONFIG__COMMAND_MIN                             0u /* 1 */
#define OD_TRACE_CONFIG__COMMAND_MAX                             2u /* 1 */
#define OD_TRACE_CONFIG__COMMAND_REF                             0x21000908UL
#define OD_TRACE_CONFIG__COMMAND_STOP                            0u
#define OD_TRACE_CONFIG__COMMAND_ARM                             1u
#define OD_TRACE_CONFIG__COMMAND_FORCE_TRIGGER                   2u
/* 0x2100:0A trace_config.state UNSIGNED8 ro [1] */
#define OD_TRACE_CONFIG__STATE_INDEX                             0x2100u
#define OD_TRACE_CONFIG__STATE_SUB                               0x0Au
#define OD_TRACE_CONFIG__STATE_TYPE                              OD_TYPE_U8
#define OD_TRACE_CONFIG__STATE_CTYPE                             uint16_t
#define OD_TRACE_CONFIG__STATE_ACCESS                            OD_ACCESS_RO
#define OD_TRACE_CONFIG__STATE_PDO                               0u
#define OD_TRACE_CONFIG__STATE_DEFAULT                           0u /* 1 */
#define OD_TRACE_CONFIG__STATE_MIN                               0u /* 1 */
#define OD_TRACE_CONFIG__STATE_MAX                               3u /* 1 */
#define OD_TRACE_CONFIG__STATE_REF                               0x21000A08UL
#define OD_TRACE_CONFIG__STATE_IDLE                              0u
#define OD_TRACE_CONFIG__STATE_ARMED                             1u
#define OD_TRACE_CONFIG__STATE_RECORDING                         2u
#define OD_TRACE_CONFIG__STATE_DONE                              3u
/* 0x2100:0B trace_config.trigger_position UNSIGNED32 ro [samples] - sample index of the trigger within the data */
#define OD_TRACE_CONFIG__TRIGGER_POSITION_INDEX                  0x2100u
#define OD_TRACE_CONFIG__TRIGGER_POSITION_SUB                    0x0Bu
#define OD_TRACE_CONFIG__TRIGGER_POSITION_TYPE                   OD_TYPE_U32
#define OD_TRACE_CONFIG__TRIGGER_POSITION_CTYPE                  uint32_t
#define OD_TRACE_CONFIG__TRIGGER_POSITION_ACCESS                 OD_ACCESS_RO
#define OD_TRACE_CONFIG__TRIGGER_POSITION_PDO                    0u
#define OD_TRACE_CONFIG__TRIGGER_POSITION_DEFAULT                0x00000000UL /* samples */
#define OD_TRACE_CONFIG__TRIGGER_POSITION_REF                    0x21000B20UL
/* 0x2100:0C trace_config.capacity UNSIGNED32 ro [samples] - REAL32 samples, all channels (64 KiB XINTF SRAM) */
#define OD_TRACE_CONFIG__CAPACITY_INDEX                          0x2100u
#define OD_TRACE_CONFIG__CAPACITY_SUB                            0x0Cu
#define OD_TRACE_CONFIG__CAPACITY_TYPE                           OD_TYPE_U32
#define OD_TRACE_CONFIG__CAPACITY_CTYPE                          uint32_t
#define OD_TRACE_CONFIG__CAPACITY_ACCESS                         OD_ACCESS_RO
#define OD_TRACE_CONFIG__CAPACITY_PDO                            0u
#define OD_TRACE_CONFIG__CAPACITY_DEFAULT                        0x00004000UL /* samples */
#define OD_TRACE_CONFIG__CAPACITY_REF                            0x21000C20UL
/* 0x2100:0D trace_config.pre_trigger_filled UNSIGNED16 ro [samples] - trace samples held before the trigger: rises from 0 after arm to pre_trigger (in drive time, divider loop periods per sample); a crossing or setpoint-step trigger is accepted only once it equals pre_trigger; 0 when idle */
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_INDEX                0x2100u
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_SUB                  0x0Du
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_TYPE                 OD_TYPE_U16
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_CTYPE                uint16_t
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_ACCESS               OD_ACCESS_RO
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_PDO                  0u
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_DEFAULT              0u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_MIN                  0u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_MAX                  16384u /* samples */
#define OD_TRACE_CONFIG__PRE_TRIGGER_FILLED_REF                  0x21000D10UL

/* ---- 0x2101 trace_channels ---- */
#define OD_TRACE_CHANNELS_INDEX                                  0x2101u
/* 0x2101:00 trace_channels.highest_sub_index UNSIGNED8 const */
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_INDEX               0x2101u
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_SUB                 0x00u
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_TYPE                OD_TYPE_U8
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_CTYPE               uint16_t
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_ACCESS              OD_ACCESS_CONST
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_PDO                 0u
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_DEFAULT             8u
#define OD_TRACE_CHANNELS__HIGHEST_SUB_INDEX_REF                 0x21010008UL
/* 0x2101:01 trace_channels.channel_1 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_1_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_1_SUB                         0x01u
#define OD_TRACE_CHANNELS__CHANNEL_1_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_1_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_1_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_1_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_1_DEFAULT                     0x20400120UL
#define OD_TRACE_CHANNELS__CHANNEL_1_REF                         0x21010120UL
/* 0x2101:02 trace_channels.channel_2 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_2_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_2_SUB                         0x02u
#define OD_TRACE_CHANNELS__CHANNEL_2_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_2_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_2_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_2_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_2_DEFAULT                     0x20400A20UL
#define OD_TRACE_CHANNELS__CHANNEL_2_REF                         0x21010220UL
/* 0x2101:03 trace_channels.channel_3 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_3_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_3_SUB                         0x03u
#define OD_TRACE_CHANNELS__CHANNEL_3_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_3_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_3_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_3_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_3_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_3_REF                         0x21010320UL
/* 0x2101:04 trace_channels.channel_4 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_4_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_4_SUB                         0x04u
#define OD_TRACE_CHANNELS__CHANNEL_4_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_4_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_4_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_4_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_4_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_4_REF                         0x21010420UL
/* 0x2101:05 trace_channels.channel_5 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_5_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_5_SUB                         0x05u
#define OD_TRACE_CHANNELS__CHANNEL_5_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_5_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_5_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_5_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_5_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_5_REF                         0x21010520UL
/* 0x2101:06 trace_channels.channel_6 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_6_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_6_SUB                         0x06u
#define OD_TRACE_CHANNELS__CHANNEL_6_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_6_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_6_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_6_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_6_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_6_REF                         0x21010620UL
/* 0x2101:07 trace_channels.channel_7 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_7_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_7_SUB                         0x07u
#define OD_TRACE_CHANNELS__CHANNEL_7_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_7_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_7_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_7_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_7_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_7_REF                         0x21010720UL
/* 0x2101:08 trace_channels.channel_8 UNSIGNED32 rw - OD reference index<<16 | sub<<8 | bit length, 0 = unused */
#define OD_TRACE_CHANNELS__CHANNEL_8_INDEX                       0x2101u
#define OD_TRACE_CHANNELS__CHANNEL_8_SUB                         0x08u
#define OD_TRACE_CHANNELS__CHANNEL_8_TYPE                        OD_TYPE_U32
#define OD_TRACE_CHANNELS__CHANNEL_8_CTYPE                       uint32_t
#define OD_TRACE_CHANNELS__CHANNEL_8_ACCESS                      OD_ACCESS_RW
#define OD_TRACE_CHANNELS__CHANNEL_8_PDO                         0u
#define OD_TRACE_CHANNELS__CHANNEL_8_DEFAULT                     0x00000000UL
#define OD_TRACE_CHANNELS__CHANNEL_8_REF                         0x21010820UL

/* ---- 0x2102 trace_data ---- */
/* 0x2102:00 trace_data DOMAIN ro - little-endian REAL32, sample-major (s0c0, s0c1, ...), oldest first, length * channel_count * 4 bytes */
#define OD_TRACE_DATA_INDEX                                      0x2102u
#define OD_TRACE_DATA_SUB                                        0x00u
#define OD_TRACE_DATA_TYPE                                       OD_TYPE_DOMAIN
#define OD_TRACE_DATA_ACCESS                                     OD_ACCESS_RO
#define OD_TRACE_DATA_PDO                                        0u

/* ---- 0x5000 sim_load ---- */
#define OD_SIM_LOAD_INDEX                                        0x5000u
/* 0x5000:00 sim_load.highest_sub_index UNSIGNED8 const */
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_INDEX                     0x5000u
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_SUB                       0x00u
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_TYPE                      OD_TYPE_U8
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_CTYPE                     uint16_t
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_ACCESS                    OD_ACCESS_CONST
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_PDO                       0u
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_DEFAULT                   4u
#define OD_SIM_LOAD__HIGHEST_SUB_INDEX_REF                       0x50000008UL
/* 0x5000:01 sim_load.T_load REAL32 rw [N*m] - constant load torque, a write is a load step */
#define OD_SIM_LOAD__T_LOAD_INDEX                                0x5000u
#define OD_SIM_LOAD__T_LOAD_SUB                                  0x01u
#define OD_SIM_LOAD__T_LOAD_TYPE                                 OD_TYPE_REAL32
#define OD_SIM_LOAD__T_LOAD_CTYPE                                float
#define OD_SIM_LOAD__T_LOAD_ACCESS                               OD_ACCESS_RW
#define OD_SIM_LOAD__T_LOAD_PDO                                  0u
#define OD_SIM_LOAD__T_LOAD_DEFAULT                              0.0f /* N*m */
#define OD_SIM_LOAD__T_LOAD_MIN                                  (-50.0f) /* N*m */
#define OD_SIM_LOAD__T_LOAD_MAX                                  50.0f /* N*m */
#define OD_SIM_LOAD__T_LOAD_REF                                  0x50000120UL
/* 0x5000:02 sim_load.k_gen REAL32 rw [N*m/rpm] - DC-generator load torque k_gen * speed, default 90 % of the speed-proportional torque identified in the paper (a = 0.9999785) */
#define OD_SIM_LOAD__K_GEN_INDEX                                 0x5000u
#define OD_SIM_LOAD__K_GEN_SUB                                   0x02u
#define OD_SIM_LOAD__K_GEN_TYPE                                  OD_TYPE_REAL32
#define OD_SIM_LOAD__K_GEN_CTYPE                                 float
#define OD_SIM_LOAD__K_GEN_ACCESS                                OD_ACCESS_RW
#define OD_SIM_LOAD__K_GEN_PDO                                   0u
#define OD_SIM_LOAD__K_GEN_DEFAULT                               0.006921f /* N*m/rpm */
#define OD_SIM_LOAD__K_GEN_MIN                                   0.0f /* N*m/rpm */
#define OD_SIM_LOAD__K_GEN_MAX                                   1.0f /* N*m/rpm */
#define OD_SIM_LOAD__K_GEN_CONFIG_ONLY                           1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_LOAD__K_GEN_REF                                   0x50000220UL
/* 0x5000:03 sim_load.J REAL32 rw [kg*m^2] - total inertia, default from the paper's identified b = 3.33715e-4 rpm/(A sample); up to 1e4 holds the rotor (constant speed, as the paper's current steps at low speed) */
#define OD_SIM_LOAD__J_INDEX                                     0x5000u
#define OD_SIM_LOAD__J_SUB                                       0x03u
#define OD_SIM_LOAD__J_TYPE                                      OD_TYPE_REAL32
#define OD_SIM_LOAD__J_CTYPE                                     float
#define OD_SIM_LOAD__J_ACCESS                                    OD_ACCESS_RW
#define OD_SIM_LOAD__J_PDO                                       0u
#define OD_SIM_LOAD__J_DEFAULT                                   0.06831f /* kg*m^2 */
#define OD_SIM_LOAD__J_MIN                                       1e-05f /* kg*m^2 */
#define OD_SIM_LOAD__J_MAX                                       10000.0f /* kg*m^2 */
#define OD_SIM_LOAD__J_CONFIG_ONLY                               1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_LOAD__J_REF                                       0x50000320UL
/* 0x5000:04 sim_load.B REAL32 rw [N*m*s/rad] - viscous friction, default 10 % of the speed-proportional torque identified in the paper (a = 0.9999785) */
#define OD_SIM_LOAD__B_INDEX                                     0x5000u
#define OD_SIM_LOAD__B_SUB                                       0x04u
#define OD_SIM_LOAD__B_TYPE                                      OD_TYPE_REAL32
#define OD_SIM_LOAD__B_CTYPE                                     float
#define OD_SIM_LOAD__B_ACCESS                                    OD_ACCESS_RW
#define OD_SIM_LOAD__B_PDO                                       0u
#define OD_SIM_LOAD__B_DEFAULT                                   0.007344f /* N*m*s/rad */
#define OD_SIM_LOAD__B_MIN                                       0.0f /* N*m*s/rad */
#define OD_SIM_LOAD__B_MAX                                       10.0f /* N*m*s/rad */
#define OD_SIM_LOAD__B_CONFIG_ONLY                               1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_LOAD__B_REF                                       0x50000420UL

/* ---- 0x5010 sim_fault ---- */
#define OD_SIM_FAULT_INDEX                                       0x5010u
/* 0x5010:00 sim_fault.highest_sub_index UNSIGNED8 const */
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_INDEX                    0x5010u
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_SUB                      0x00u
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_TYPE                     OD_TYPE_U8
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_CTYPE                    uint16_t
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_ACCESS                   OD_ACCESS_CONST
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_PDO                      0u
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_DEFAULT                  2u
#define OD_SIM_FAULT__HIGHEST_SUB_INDEX_REF                      0x50100008UL
/* 0x5010:01 sim_fault.inject UNSIGNED8 rw [1] */
#define OD_SIM_FAULT__INJECT_INDEX                               0x5010u
#define OD_SIM_FAULT__INJECT_SUB                                 0x01u
#define OD_SIM_FAULT__INJECT_TYPE                                OD_TYPE_U8
#define OD_SIM_FAULT__INJECT_CTYPE                               uint16_t
#define OD_SIM_FAULT__INJECT_ACCESS                              OD_ACCESS_RW
#define OD_SIM_FAULT__INJECT_PDO                                 0u
#define OD_SIM_FAULT__INJECT_DEFAULT                             0u /* 1 */
#define OD_SIM_FAULT__INJECT_MIN                                 0u /* 1 */
#define OD_SIM_FAULT__INJECT_MAX                                 3u /* 1 */
#define OD_SIM_FAULT__INJECT_REF                                 0x50100108UL
#define OD_SIM_FAULT__INJECT_NONE                                0u
#define OD_SIM_FAULT__INJECT_OVERCURRENT                         1u
#define OD_SIM_FAULT__INJECT_DC_OVERVOLTAGE                      2u
#define OD_SIM_FAULT__INJECT_DC_UNDERVOLTAGE                     3u
/* 0x5010:02 sim_fault.V_dc_supply REAL32 rw [V] - virtual DC supply voltage (at least 1 V: the modulation index is normalised by it) */
#define OD_SIM_FAULT__V_DC_SUPPLY_INDEX                          0x5010u
#define OD_SIM_FAULT__V_DC_SUPPLY_SUB                            0x02u
#define OD_SIM_FAULT__V_DC_SUPPLY_TYPE                           OD_TYPE_REAL32
#define OD_SIM_FAULT__V_DC_SUPPLY_CTYPE                          float
#define OD_SIM_FAULT__V_DC_SUPPLY_ACCESS                         OD_ACCESS_RW
#define OD_SIM_FAULT__V_DC_SUPPLY_PDO                            0u
#define OD_SIM_FAULT__V_DC_SUPPLY_DEFAULT                        48.0f /* V */
#define OD_SIM_FAULT__V_DC_SUPPLY_MIN                            1.0f /* V */
#define OD_SIM_FAULT__V_DC_SUPPLY_MAX                            100.0f /* V */
#define OD_SIM_FAULT__V_DC_SUPPLY_REF                            0x50100220UL

/* ---- 0x5020 sim_inverter ---- */
#define OD_SIM_INVERTER_INDEX                                    0x5020u
/* 0x5020:00 sim_inverter.highest_sub_index UNSIGNED8 const */
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_INDEX                 0x5020u
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_SUB                   0x00u
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_TYPE                  OD_TYPE_U8
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_CTYPE                 uint16_t
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_ACCESS                OD_ACCESS_CONST
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_PDO                   0u
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_DEFAULT               4u
#define OD_SIM_INVERTER__HIGHEST_SUB_INDEX_REF                   0x50200008UL
/* 0x5020:01 sim_inverter.T_BT REAL32 rw [s] - virtual inverter blanking time (at most Ts/4: each blanking interval within a quarter PWM period) */
#define OD_SIM_INVERTER__T_BT_INDEX                              0x5020u
#define OD_SIM_INVERTER__T_BT_SUB                                0x01u
#define OD_SIM_INVERTER__T_BT_TYPE                               OD_TYPE_REAL32
#define OD_SIM_INVERTER__T_BT_CTYPE                              float
#define OD_SIM_INVERTER__T_BT_ACCESS                             OD_ACCESS_RW
#define OD_SIM_INVERTER__T_BT_PDO                                0u
#define OD_SIM_INVERTER__T_BT_DEFAULT                            0.0f /* s */
#define OD_SIM_INVERTER__T_BT_MIN                                0.0f /* s */
#define OD_SIM_INVERTER__T_BT_MAX                                5e-06f /* s */
#define OD_SIM_INVERTER__T_BT_CONFIG_ONLY                        1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_INVERTER__T_BT_REF                                0x50200120UL
/* 0x5020:02 sim_inverter.T_DD REAL32 rw [s] - virtual inverter driver delay */
#define OD_SIM_INVERTER__T_DD_INDEX                              0x5020u
#define OD_SIM_INVERTER__T_DD_SUB                                0x02u
#define OD_SIM_INVERTER__T_DD_TYPE                               OD_TYPE_REAL32
#define OD_SIM_INVERTER__T_DD_CTYPE                              float
#define OD_SIM_INVERTER__T_DD_ACCESS                             OD_ACCESS_RW
#define OD_SIM_INVERTER__T_DD_PDO                                0u
#define OD_SIM_INVERTER__T_DD_DEFAULT                            0.0f /* s */
#define OD_SIM_INVERTER__T_DD_MIN                                0.0f /* s */
#define OD_SIM_INVERTER__T_DD_MAX                                2e-05f /* s */
#define OD_SIM_INVERTER__T_DD_CONFIG_ONLY                        1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_INVERTER__T_DD_REF                                0x50200220UL
/* 0x5020:03 sim_inverter.T_SD REAL32 rw [s] - virtual sampling delay */
#define OD_SIM_INVERTER__T_SD_INDEX                              0x5020u
#define OD_SIM_INVERTER__T_SD_SUB                                0x03u
#define OD_SIM_INVERTER__T_SD_TYPE                               OD_TYPE_REAL32
#define OD_SIM_INVERTER__T_SD_CTYPE                              float
#define OD_SIM_INVERTER__T_SD_ACCESS                             OD_ACCESS_RW
#define OD_SIM_INVERTER__T_SD_PDO                                0u
#define OD_SIM_INVERTER__T_SD_DEFAULT                            0.0f /* s */
#define OD_SIM_INVERTER__T_SD_MIN                                0.0f /* s */
#define OD_SIM_INVERTER__T_SD_MAX                                2e-05f /* s */
#define OD_SIM_INVERTER__T_SD_CONFIG_ONLY                        1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_INVERTER__T_SD_REF                                0x50200320UL
/* 0x5020:04 sim_inverter.V_G REAL32 rw [V] - virtual switch voltage drop */
#define OD_SIM_INVERTER__V_G_INDEX                               0x5020u
#define OD_SIM_INVERTER__V_G_SUB                                 0x04u
#define OD_SIM_INVERTER__V_G_TYPE                                OD_TYPE_REAL32
#define OD_SIM_INVERTER__V_G_CTYPE                               float
#define OD_SIM_INVERTER__V_G_ACCESS                              OD_ACCESS_RW
#define OD_SIM_INVERTER__V_G_PDO                                 0u
#define OD_SIM_INVERTER__V_G_DEFAULT                             0.0f /* V */
#define OD_SIM_INVERTER__V_G_MIN                                 0.0f /* V */
#define OD_SIM_INVERTER__V_G_MAX                                 5.0f /* V */
#define OD_SIM_INVERTER__V_G_CONFIG_ONLY                         1u /* write only with the power stage off, else 0x08000022 */
#define OD_SIM_INVERTER__V_G_REF                                 0x50200420UL

/* ---- 0x5030 sim_info ---- */
#define OD_SIM_INFO_INDEX                                        0x5030u
/* 0x5030:00 sim_info.highest_sub_index UNSIGNED8 const */
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_INDEX                     0x5030u
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_SUB                       0x00u
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_TYPE                      OD_TYPE_U8
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_CTYPE                     uint16_t
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_ACCESS                    OD_ACCESS_CONST
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_PDO                       0u
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_DEFAULT                   3u
#define OD_SIM_INFO__HIGHEST_SUB_INDEX_REF                       0x50300008UL
/* 0x5030:01 sim_info.sim_time REAL32 ro [s] */
#define OD_SIM_INFO__SIM_TIME_INDEX                              0x5030u
#define OD_SIM_INFO__SIM_TIME_SUB                                0x01u
#define OD_SIM_INFO__SIM_TIME_TYPE                               OD_TYPE_REAL32
#define OD_SIM_INFO__SIM_TIME_CTYPE                              float
#define OD_SIM_INFO__SIM_TIME_ACCESS                             OD_ACCESS_RO
#define OD_SIM_INFO__SIM_TIME_PDO                                0u
#define OD_SIM_INFO__SIM_TIME_DEFAULT                            0.0f /* s */
#define OD_SIM_INFO__SIM_TIME_MIN                                0.0f /* s */
#define OD_SIM_INFO__SIM_TIME_MAX                                3.4e+38f /* s */
#define OD_SIM_INFO__SIM_TIME_REF                                0x50300120UL
/* 0x5030:02 sim_info.speed_factor REAL32 ro [1] - simulated time per wall-clock time */
#define OD_SIM_INFO__SPEED_FACTOR_INDEX                          0x5030u
#define OD_SIM_INFO__SPEED_FACTOR_SUB                            0x02u
#define OD_SIM_INFO__SPEED_FACTOR_TYPE                           OD_TYPE_REAL32
#define OD_SIM_INFO__SPEED_FACTOR_CTYPE                          float
#define OD_SIM_INFO__SPEED_FACTOR_ACCESS                         OD_ACCESS_RO
#define OD_SIM_INFO__SPEED_FACTOR_PDO                            0u
#define OD_SIM_INFO__SPEED_FACTOR_DEFAULT                        0.0f /* 1 */
#define OD_SIM_INFO__SPEED_FACTOR_MIN                            0.0f /* 1 */
#define OD_SIM_INFO__SPEED_FACTOR_MAX                            1000000.0f /* 1 */
#define OD_SIM_INFO__SPEED_FACTOR_REF                            0x50300220UL
/* 0x5030:03 sim_info.model UNSIGNED8 rw [1] */
#define OD_SIM_INFO__MODEL_INDEX                                 0x5030u
#define OD_SIM_INFO__MODEL_SUB                                   0x03u
#define OD_SIM_INFO__MODEL_TYPE                                  OD_TYPE_U8
#define OD_SIM_INFO__MODEL_CTYPE                                 uint16_t
#define OD_SIM_INFO__MODEL_ACCESS                                OD_ACCESS_RW
#define OD_SIM_INFO__MODEL_PDO                                   0u
#define OD_SIM_INFO__MODEL_DEFAULT                               0u /* 1 */
#define OD_SIM_INFO__MODEL_MIN                                   0u /* 1 */
#define OD_SIM_INFO__MODEL_MAX                                   1u /* 1 */
#define OD_SIM_INFO__MODEL_REF                                   0x50300308UL
#define OD_SIM_INFO__MODEL_PWM_EXACT                             0u
#define OD_SIM_INFO__MODEL_AVERAGED                              1u

/* ---- 0x6007 abort_connection_option_code ---- */
/* 0x6007:00 abort_connection_option_code INTEGER16 rw - 0 none, 1 fault, 2 disable voltage, 3 quick stop */
#define OD_ABORT_CONNECTION_OPTION_CODE_INDEX                    0x6007u
#define OD_ABORT_CONNECTION_OPTION_CODE_SUB                      0x00u
#define OD_ABORT_CONNECTION_OPTION_CODE_TYPE                     OD_TYPE_I16
#define OD_ABORT_CONNECTION_OPTION_CODE_CTYPE                    int16_t
#define OD_ABORT_CONNECTION_OPTION_CODE_ACCESS                   OD_ACCESS_RW
#define OD_ABORT_CONNECTION_OPTION_CODE_PDO                      0u
#define OD_ABORT_CONNECTION_OPTION_CODE_DEFAULT                  3
#define OD_ABORT_CONNECTION_OPTION_CODE_MIN                      0
#define OD_ABORT_CONNECTION_OPTION_CODE_MAX                      3
#define OD_ABORT_CONNECTION_OPTION_CODE_REF                      0x60070010UL

/* ---- 0x603F error_code ---- */
/* 0x603F:00 error_code UNSIGNED16 ro - last EMCY error code */
#define OD_ERROR_CODE_INDEX                                      0x603Fu
#define OD_ERROR_CODE_SUB                                        0x00u
#define OD_ERROR_CODE_TYPE                                       OD_TYPE_U16
#define OD_ERROR_CODE_CTYPE                                      uint16_t
#define OD_ERROR_CODE_ACCESS                                     OD_ACCESS_RO
#define OD_ERROR_CODE_PDO                                        1u
#define OD_ERROR_CODE_DEFAULT                                    0u
#define OD_ERROR_CODE_REF                                        0x603F0010UL

/* ---- 0x6040 controlword ---- */
/* 0x6040:00 controlword UNSIGNED16 rw */
#define OD_CONTROLWORD_INDEX                                     0x6040u
#define OD_CONTROLWORD_SUB                                       0x00u
#define OD_CONTROLWORD_TYPE                                      OD_TYPE_U16
#define OD_CONTROLWORD_CTYPE                                     uint16_t
#define OD_CONTROLWORD_ACCESS                                    OD_ACCESS_RW
#define OD_CONTROLWORD_PDO                                       1u
#define OD_CONTROLWORD_DEFAULT                                   0u
#define OD_CONTROLWORD_REF                                       0x60400010UL

/* ---- 0x6041 statusword ---- */
/* 0x6041:00 statusword UNSIGNED16 ro */
#define OD_STATUSWORD_INDEX                                      0x6041u
#define OD_STATUSWORD_SUB                                        0x00u
#define OD_STATUSWORD_TYPE                                       OD_TYPE_U16
#define OD_STATUSWORD_CTYPE                                      uint16_t
#define OD_STATUSWORD_ACCESS                                     OD_ACCESS_RO
#define OD_STATUSWORD_PDO                                        1u
#define OD_STATUSWORD_DEFAULT                                    0u
#define OD_STATUSWORD_REF                                        0x60410010UL

/* ---- 0x605A quick_stop_option_code ---- */
/* 0x605A:00 quick_stop_option_code INTEGER16 rw */
#define OD_QUICK_STOP_OPTION_CODE_INDEX                          0x605Au
#define OD_QUICK_STOP_OPTION_CODE_SUB                            0x00u
#define OD_QUICK_STOP_OPTION_CODE_TYPE                           OD_TYPE_I16
#define OD_QUICK_STOP_OPTION_CODE_CTYPE                          int16_t
#define OD_QUICK_STOP_OPTION_CODE_ACCESS                         OD_ACCESS_RW
#define OD_QUICK_STOP_OPTION_CODE_PDO                            0u
#define OD_QUICK_STOP_OPTION_CODE_DEFAULT                        2
#define OD_QUICK_STOP_OPTION_CODE_MIN                            0
#define OD_QUICK_STOP_OPTION_CODE_MAX                            8
#define OD_QUICK_STOP_OPTION_CODE_REF                            0x605A0010UL

/* ---- 0x605B shutdown_option_code ---- */
/* 0x605B:00 shutdown_option_code INTEGER16 rw */
#define OD_SHUTDOWN_OPTION_CODE_INDEX                            0x605Bu
#define OD_SHUTDOWN_OPTION_CODE_SUB                              0x00u
#define OD_SHUTDOWN_OPTION_CODE_TYPE                             OD_TYPE_I16
#define OD_SHUTDOWN_OPTION_CODE_CTYPE                            int16_t
#define OD_SHUTDOWN_OPTION_CODE_ACCESS                           OD_ACCESS_RW
#define OD_SHUTDOWN_OPTION_CODE_PDO                              0u
#define OD_SHUTDOWN_OPTION_CODE_DEFAULT                          0
#define OD_SHUTDOWN_OPTION_CODE_MIN                              0
#define OD_SHUTDOWN_OPTION_CODE_MAX                              1
#define OD_SHUTDOWN_OPTION_CODE_REF                              0x605B0010UL

/* ---- 0x605C disable_operation_option_code ---- */
/* 0x605C:00 disable_operation_option_code INTEGER16 rw */
#define OD_DISABLE_OPERATION_OPTION_CODE_INDEX                   0x605Cu
#define OD_DISABLE_OPERATION_OPTION_CODE_SUB                     0x00u
#define OD_DISABLE_OPERATION_OPTION_CODE_TYPE                    OD_TYPE_I16
#define OD_DISABLE_OPERATION_OPTION_CODE_CTYPE                   int16_t
#define OD_DISABLE_OPERATION_OPTION_CODE_ACCESS                  OD_ACCESS_RW
#define OD_DISABLE_OPERATION_OPTION_CODE_PDO                     0u
#define OD_DISABLE_OPERATION_OPTION_CODE_DEFAULT                 1
#define OD_DISABLE_OPERATION_OPTION_CODE_MIN                     0
#define OD_DISABLE_OPERATION_OPTION_CODE_MAX                     1
#define OD_DISABLE_OPERATION_OPTION_CODE_REF                     0x605C0010UL

/* ---- 0x605D halt_option_code ---- */
/* 0x605D:00 halt_option_code INTEGER16 rw - controlword bit 8 (halt): 1 slow-down ramp (0x6084), 2 quick-stop ramp (0x6085), 3/4 act as 2; then hold 0 in OPERATION ENABLED */
#define OD_HALT_OPTION_CODE_INDEX                                0x605Du
#define OD_HALT_OPTION_CODE_SUB                                  0x00u
#define OD_HALT_OPTION_CODE_TYPE                                 OD_TYPE_I16
#define OD_HALT_OPTION_CODE_CTYPE                                int16_t
#define OD_HALT_OPTION_CODE_ACCESS                               OD_ACCESS_RW
#define OD_HALT_OPTION_CODE_PDO                                  0u
#define OD_HALT_OPTION_CODE_DEFAULT                              1
#define OD_HALT_OPTION_CODE_MIN                                  1
#define OD_HALT_OPTION_CODE_MAX                                  4
#define OD_HALT_OPTION_CODE_REF                                  0x605D0010UL

/* ---- 0x605E fault_reaction_option_code ---- */
/* 0x605E:00 fault_reaction_option_code INTEGER16 rw */
#define OD_FAULT_REACTION_OPTION_CODE_INDEX                      0x605Eu
#define OD_FAULT_REACTION_OPTION_CODE_SUB                        0x00u
#define OD_FAULT_REACTION_OPTION_CODE_TYPE                       OD_TYPE_I16
#define OD_FAULT_REACTION_OPTION_CODE_CTYPE                      int16_t
#define OD_FAULT_REACTION_OPTION_CODE_ACCESS                     OD_ACCESS_RW
#define OD_FAULT_REACTION_OPTION_CODE_PDO                        0u
#define OD_FAULT_REACTION_OPTION_CODE_DEFAULT                    2
#define OD_FAULT_REACTION_OPTION_CODE_MIN                        0
#define OD_FAULT_REACTION_OPTION_CODE_MAX                        4
#define OD_FAULT_REACTION_OPTION_CODE_REF                        0x605E0010UL

/* ---- 0x6060 modes_of_operation ---- */
/* 0x6060:00 modes_of_operation INTEGER8 rw - 3 profile velocity (IP speed loop), 4 profile torque (i_p* = target_torque/1000 * rated current), -1 pseudo-current (i_p* = setpoints.i_p_ref) */
#define OD_MODES_OF_OPERATION_INDEX                              0x6060u
#define OD_MODES_OF_OPERATION_SUB                                0x00u
#define OD_MODES_OF_OPERATION_TYPE                               OD_TYPE_I8
#define OD_MODES_OF_OPERATION_CTYPE                              int16_t
#define OD_MODES_OF_OPERATION_ACCESS                             OD_ACCESS_RW
#define OD_MODES_OF_OPERATION_PDO                                1u
#define OD_MODES_OF_OPERATION_DEFAULT                            3
#define OD_MODES_OF_OPERATION_MIN                                (-1)
#define OD_MODES_OF_OPERATION_MAX                                4
#define OD_MODES_OF_OPERATION_REF                                0x60600008UL
#define OD_MODES_OF_OPERATION_PSEUDO_CURRENT                     (-1)
#define OD_MODES_OF_OPERATION_PROFILE_VELOCITY                   3
#define OD_MODES_OF_OPERATION_PROFILE_TORQUE                     4

/* ---- 0x6061 modes_of_operation_display ---- */
/* 0x6061:00 modes_of_operation_display INTEGER8 ro */
#define OD_MODES_OF_OPERATION_DISPLAY_INDEX                      0x6061u
#define OD_MODES_OF_OPERATION_DISPLAY_SUB                        0x00u
#define OD_MODES_OF_OPERATION_DISPLAY_TYPE                       OD_TYPE_I8
#define OD_MODES_OF_OPERATION_DISPLAY_CTYPE                      int16_t
#define OD_MODES_OF_OPERATION_DISPLAY_ACCESS                     OD_ACCESS_RO
#define OD_MODES_OF_OPERATION_DISPLAY_PDO                        1u
#define OD_MODES_OF_OPERATION_DISPLAY_DEFAULT                    3
#define OD_MODES_OF_OPERATION_DISPLAY_MIN                        (-1)
#define OD_MODES_OF_OPERATION_DISPLAY_MAX                        4
#define OD_MODES_OF_OPERATION_DISPLAY_REF                        0x60610008UL
#define OD_MODES_OF_OPERATION_DISPLAY_PSEUDO_CURRENT             (-1)
#define OD_MODES_OF_OPERATION_DISPLAY_PROFILE_VELOCITY           3
#define OD_MODES_OF_OPERATION_DISPLAY_PROFILE_TORQUE             4

/* ---- 0x606C velocity_actual_value ---- */
/* 0x606C:00 velocity_actual_value INTEGER32 ro [rpm] */
#define OD_VELOCITY_ACTUAL_VALUE_INDEX                           0x606Cu
#define OD_VELOCITY_ACTUAL_VALUE_SUB                             0x00u
#define OD_VELOCITY_ACTUAL_VALUE_TYPE                            OD_TYPE_I32
#define OD_VELOCITY_ACTUAL_VALUE_CTYPE                           int32_t
#define OD_VELOCITY_ACTUAL_VALUE_ACCESS                          OD_ACCESS_RO
#define OD_VELOCITY_ACTUAL_VALUE_PDO                             1u
#define OD_VELOCITY_ACTUAL_VALUE_DEFAULT                         0L /* rpm */
#define OD_VELOCITY_ACTUAL_VALUE_REF                             0x606C0020UL

/* ---- 0x606D velocity_window ---- */
/* 0x606D:00 velocity_window UNSIGNED16 rw [rpm] - target reached (statusword bit 10, profile velocity) when |speed - target| <= window for velocity_window_time */
#define OD_VELOCITY_WINDOW_INDEX                                 0x606Du
#define OD_VELOCITY_WINDOW_SUB                                   0x00u
#define OD_VELOCITY_WINDOW_TYPE                                  OD_TYPE_U16
#define OD_VELOCITY_WINDOW_CTYPE                                 uint16_t
#define OD_VELOCITY_WINDOW_ACCESS                                OD_ACCESS_RW
#define OD_VELOCITY_WINDOW_PDO                                   0u
#define OD_VELOCITY_WINDOW_DEFAULT                               20u /* rpm */
#define OD_VELOCITY_WINDOW_MIN                                   0u /* rpm */
#define OD_VELOCITY_WINDOW_MAX                                   6000u /* rpm */
#define OD_VELOCITY_WINDOW_REF                                   0x606D0010UL

/* ---- 0x606E velocity_window_time ---- */
/* 0x606E:00 velocity_window_time UNSIGNED16 rw [ms] - time |speed - target| must stay within velocity_window before bit 10 is set */
#define OD_VELOCITY_WINDOW_TIME_INDEX                            0x606Eu
#define OD_VELOCITY_WINDOW_TIME_SUB                              0x00u
#define OD_VELOCITY_WINDOW_TIME_TYPE                             OD_TYPE_U16
#define OD_VELOCITY_WINDOW_TIME_CTYPE                            uint16_t
#define OD_VELOCITY_WINDOW_TIME_ACCESS                           OD_ACCESS_RW
#define OD_VELOCITY_WINDOW_TIME_PDO                              0u
#define OD_VELOCITY_WINDOW_TIME_DEFAULT                          0u /* ms */
#define OD_VELOCITY_WINDOW_TIME_MIN                              0u /* ms */
#define OD_VELOCITY_WINDOW_TIME_MAX                              60000u /* ms */
#define OD_VELOCITY_WINDOW_TIME_REF                              0x606E0010UL

/* ---- 0x606F velocity_threshold ---- */
/* 0x606F:00 velocity_threshold UNSIGNED16 rw [rpm] - speed = 0 (statusword bit 12, profile velocity) when |speed| <= threshold for velocity_threshold_time */
#define OD_VELOCITY_THRESHOLD_INDEX                              0x606Fu
#define OD_VELOCITY_THRESHOLD_SUB                                0x00u
#define OD_VELOCITY_THRESHOLD_TYPE                               OD_TYPE_U16
#define OD_VELOCITY_THRESHOLD_CTYPE                              uint16_t
#define OD_VELOCITY_THRESHOLD_ACCESS                             OD_ACCESS_RW
#define OD_VELOCITY_THRESHOLD_PDO                                0u
#define OD_VELOCITY_THRESHOLD_DEFAULT                            10u /* rpm */
#define OD_VELOCITY_THRESHOLD_MIN                                0u /* rpm */
#define OD_VELOCITY_THRESHOLD_MAX                                6000u /* rpm */
#define OD_VELOCITY_THRESHOLD_REF                                0x606F0010UL

/* ---- 0x6070 velocity_threshold_time ---- */
/* 0x6070:00 velocity_threshold_time UNSIGNED16 rw [ms] - time |speed| must stay within velocity_threshold before bit 12 is set */
#define OD_VELOCITY_THRESHOLD_TIME_INDEX                         0x6070u
#define OD_VELOCITY_THRESHOLD_TIME_SUB                           0x00u
#define OD_VELOCITY_THRESHOLD_TIME_TYPE                          OD_TYPE_U16
#define OD_VELOCITY_THRESHOLD_TIME_CTYPE                         uint16_t
#define OD_VELOCITY_THRESHOLD_TIME_ACCESS                        OD_ACCESS_RW
#define OD_VELOCITY_THRESHOLD_TIME_PDO                           0u
#define OD_VELOCITY_THRESHOLD_TIME_DEFAULT                       0u /* ms */
#define OD_VELOCITY_THRESHOLD_TIME_MIN                           0u /* ms */
#define OD_VELOCITY_THRESHOLD_TIME_MAX                           60000u /* ms */
#define OD_VELOCITY_THRESHOLD_TIME_REF                           0x60700010UL

/* ---- 0x6071 target_torque ---- */
/* 0x6071:00 target_torque INTEGER16 rw [permille of motor_rated_torque] - |target_torque| <= max_torque */
#define OD_TARGET_TORQUE_INDEX                                   0x6071u
#define OD_TARGET_TORQUE_SUB                                     0x00u
#define OD_TARGET_TORQUE_TYPE                                    OD_TYPE_I16
#define OD_TARGET_TORQUE_CTYPE                                   int16_t
#define OD_TARGET_TORQUE_ACCESS                                  OD_ACCESS_RW
#define OD_TARGET_TORQUE_PDO                                     1u
#define OD_TARGET_TORQUE_DEFAULT                                 0 /* permille of motor_rated_torque */
#define OD_TARGET_TORQUE_MIN                                     (-1000) /* permille of motor_rated_torque */
#define OD_TARGET_TORQUE_MAX                                     1000 /* permille of motor_rated_torque */
#define OD_TARGET_TORQUE_REF                                     0x60710010UL

/* ---- 0x6072 max_torque ---- */
/* 0x6072:00 max_torque UNSIGNED16 rw [permille of motor_rated_torque] */
#define OD_MAX_TORQUE_INDEX                                      0x6072u
#define OD_MAX_TORQUE_SUB                                        0x00u
#define OD_MAX_TORQUE_TYPE                                       OD_TYPE_U16
#define OD_MAX_TORQUE_CTYPE                                      uint16_t
#define OD_MAX_TORQUE_ACCESS                                     OD_ACCESS_RW
#define OD_MAX_TORQUE_PDO                                        1u
#define OD_MAX_TORQUE_DEFAULT                                    1000u /* permille of motor_rated_torque */
#define OD_MAX_TORQUE_MIN                                        0u /* permille of motor_rated_torque */
#define OD_MAX_TORQUE_MAX                                        1000u /* permille of motor_rated_torque */
#define OD_MAX_TORQUE_REF                                        0x60720010UL

/* ---- 0x6073 max_current ---- */
/* 0x6073:00 max_current UNSIGNED16 rw [permille of motor_rated_current] - caps |i_p*| */
#define OD_MAX_CURRENT_INDEX                                     0x6073u
#define OD_MAX_CURRENT_SUB                                       0x00u
#define OD_MAX_CURRENT_TYPE                                      OD_TYPE_U16
#define OD_MAX_CURRENT_CTYPE                                     uint16_t
#define OD_MAX_CURRENT_ACCESS                                    OD_ACCESS_RW
#define OD_MAX_CURRENT_PDO                                       1u
#define OD_MAX_CURRENT_DEFAULT                                   1000u /* permille of motor_rated_current */
#define OD_MAX_CURRENT_MIN                                       0u /* permille of motor_rated_current */
#define OD_MAX_CURRENT_MAX                                       2000u /* permille of motor_rated_current */
#define OD_MAX_CURRENT_REF                                       0x60730010UL

/* ---- 0x6075 motor_rated_current ---- */
/* 0x6075:00 motor_rated_current UNSIGNED32 rw [mA] */
#define OD_MOTOR_RATED_CURRENT_INDEX                             0x6075u
#define OD_MOTOR_RATED_CURRENT_SUB                               0x00u
#define OD_MOTOR_RATED_CURRENT_TYPE                              OD_TYPE_U32
#define OD_MOTOR_RATED_CURRENT_CTYPE                             uint32_t
#define OD_MOTOR_RATED_CURRENT_ACCESS                            OD_ACCESS_RW
#define OD_MOTOR_RATED_CURRENT_PDO                               0u
#define OD_MOTOR_RATED_CURRENT_DEFAULT                           0x000186A0UL /* mA */
#define OD_MOTOR_RATED_CURRENT_MIN                               0x000003E8UL /* mA */
#define OD_MOTOR_RATED_CURRENT_MAX                               0x00030D40UL /* mA */
#define OD_MOTOR_RATED_CURRENT_CONFIG_ONLY                       1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR_RATED_CURRENT_REF                               0x60750020UL

/* ---- 0x6076 motor_rated_torque ---- */
/* 0x6076:00 motor_rated_torque UNSIGNED32 rw [mN*m] */
#define OD_MOTOR_RATED_TORQUE_INDEX                              0x6076u
#define OD_MOTOR_RATED_TORQUE_SUB                                0x00u
#define OD_MOTOR_RATED_TORQUE_TYPE                               OD_TYPE_U32
#define OD_MOTOR_RATED_TORQUE_CTYPE                              uint32_t
#define OD_MOTOR_RATED_TORQUE_ACCESS                             OD_ACCESS_RW
#define OD_MOTOR_RATED_TORQUE_PDO                                0u
#define OD_MOTOR_RATED_TORQUE_DEFAULT                            0x00003660UL /* mN*m */
#define OD_MOTOR_RATED_TORQUE_MIN                                0x00000064UL /* mN*m */
#define OD_MOTOR_RATED_TORQUE_MAX                                0x000186A0UL /* mN*m */
#define OD_MOTOR_RATED_TORQUE_CONFIG_ONLY                        1u /* write only with the power stage off, else 0x08000022 */
#define OD_MOTOR_RATED_TORQUE_REF                                0x60760020UL

/* ---- 0x6077 torque_actual_value ---- */
/* 0x6077:00 torque_actual_value INTEGER16 ro [permille of motor_rated_torque] */
#define OD_TORQUE_ACTUAL_VALUE_INDEX                             0x6077u
#define OD_TORQUE_ACTUAL_VALUE_SUB                               0x00u
#define OD_TORQUE_ACTUAL_VALUE_TYPE                              OD_TYPE_I16
#define OD_TORQUE_ACTUAL_VALUE_CTYPE                             int16_t
#define OD_TORQUE_ACTUAL_VALUE_ACCESS                            OD_ACCESS_RO
#define OD_TORQUE_ACTUAL_VALUE_PDO                               1u
#define OD_TORQUE_ACTUAL_VALUE_DEFAULT                           0 /* permille of motor_rated_torque */
#define OD_TORQUE_ACTUAL_VALUE_REF                               0x60770010UL

/* ---- 0x6078 current_actual_value ---- */
/* 0x6078:00 current_actual_value INTEGER16 ro [permille of motor_rated_current] - i_p */
#define OD_CURRENT_ACTUAL_VALUE_INDEX                            0x6078u
#define OD_CURRENT_ACTUAL_VALUE_SUB                              0x00u
#define OD_CURRENT_ACTUAL_VALUE_TYPE                             OD_TYPE_I16
#define OD_CURRENT_ACTUAL_VALUE_CTYPE                            int16_t
#define OD_CURRENT_ACTUAL_VALUE_ACCESS                           OD_ACCESS_RO
#define OD_CURRENT_ACTUAL_VALUE_PDO                              1u
#define OD_CURRENT_ACTUAL_VALUE_DEFAULT                          0 /* permille of motor_rated_current */
#define OD_CURRENT_ACTUAL_VALUE_REF                              0x60780010UL

/* ---- 0x6079 dc_link_circuit_voltage ---- */
/* 0x6079:00 dc_link_circuit_voltage UNSIGNED32 ro [mV] */
#define OD_DC_LINK_CIRCUIT_VOLTAGE_INDEX                         0x6079u
#define OD_DC_LINK_CIRCUIT_VOLTAGE_SUB                           0x00u
#define OD_DC_LINK_CIRCUIT_VOLTAGE_TYPE                          OD_TYPE_U32
#define OD_DC_LINK_CIRCUIT_VOLTAGE_CTYPE                         uint32_t
#define OD_DC_LINK_CIRCUIT_VOLTAGE_ACCESS                        OD_ACCESS_RO
#define OD_DC_LINK_CIRCUIT_VOLTAGE_PDO                           1u
#define OD_DC_LINK_CIRCUIT_VOLTAGE_DEFAULT                       0x00000000UL /* mV */
#define OD_DC_LINK_CIRCUIT_VOLTAGE_REF                           0x60790020UL

/* ---- 0x6080 max_motor_speed ---- */
/* 0x6080:00 max_motor_speed UNSIGNED32 rw [rpm] */
#define OD_MAX_MOTOR_SPEED_INDEX                                 0x6080u
#define OD_MAX_MOTOR_SPEED_SUB                                   0x00u
#define OD_MAX_MOTOR_SPEED_TYPE                                  OD_TYPE_U32
#define OD_MAX_MOTOR_SPEED_CTYPE                                 uint32_t
#define OD_MAX_MOTOR_SPEED_ACCESS                                OD_ACCESS_RW
#define OD_MAX_MOTOR_SPEED_PDO                                   0u
#define OD_MAX_MOTOR_SPEED_DEFAULT                               0x00000FA0UL /* rpm */
#define OD_MAX_MOTOR_SPEED_MIN                                   0x00000000UL /* rpm */
#define OD_MAX_MOTOR_SPEED_MAX                                   0x00001770UL /* rpm */
#define OD_MAX_MOTOR_SPEED_REF                                   0x60800020UL

/* ---- 0x6083 profile_acceleration ---- */
/* 0x6083:00 profile_acceleration UNSIGNED32 rw [rpm/s] - ramp applied to target_velocity before the IP loop, 0 = step */
#define OD_PROFILE_ACCELERATION_INDEX                            0x6083u
#define OD_PROFILE_ACCELERATION_SUB                              0x00u
#define OD_PROFILE_ACCELERATION_TYPE                             OD_TYPE_U32
#define OD_PROFILE_ACCELERATION_CTYPE                            uint32_t
#define OD_PROFILE_ACCELERATION_ACCESS                           OD_ACCESS_RW
#define OD_PROFILE_ACCELERATION_PDO                              0u
#define OD_PROFILE_ACCELERATION_DEFAULT                          0x00000000UL /* rpm/s */
#define OD_PROFILE_ACCELERATION_MIN                              0x00000000UL /* rpm/s */
#define OD_PROFILE_ACCELERATION_MAX                              0x000F4240UL /* rpm/s */
#define OD_PROFILE_ACCELERATION_REF                              0x60830020UL

/* ---- 0x6084 profile_deceleration ---- */
/* 0x6084:00 profile_deceleration UNSIGNED32 rw [rpm/s] - 0 = step */
#define OD_PROFILE_DECELERATION_INDEX                            0x6084u
#define OD_PROFILE_DECELERATION_SUB                              0x00u
#define OD_PROFILE_DECELERATION_TYPE                             OD_TYPE_U32
#define OD_PROFILE_DECELERATION_CTYPE                            uint32_t
#define OD_PROFILE_DECELERATION_ACCESS                           OD_ACCESS_RW
#define OD_PROFILE_DECELERATION_PDO                              0u
#define OD_PROFILE_DECELERATION_DEFAULT                          0x00000000UL /* rpm/s */
#define OD_PROFILE_DECELERATION_MIN                              0x00000000UL /* rpm/s */
#define OD_PROFILE_DECELERATION_MAX                              0x000F4240UL /* rpm/s */
#define OD_PROFILE_DECELERATION_REF                              0x60840020UL

/* ---- 0x6085 quick_stop_deceleration ---- */
/* 0x6085:00 quick_stop_deceleration UNSIGNED32 rw [rpm/s] */
#define OD_QUICK_STOP_DECELERATION_INDEX                         0x6085u
#define OD_QUICK_STOP_DECELERATION_SUB                           0x00u
#define OD_QUICK_STOP_DECELERATION_TYPE                          OD_TYPE_U32
#define OD_QUICK_STOP_DECELERATION_CTYPE                         uint32_t
#define OD_QUICK_STOP_DECELERATION_ACCESS                        OD_ACCESS_RW
#define OD_QUICK_STOP_DECELERATION_PDO                           0u
#define OD_QUICK_STOP_DECELERATION_DEFAULT                       0x00001388UL /* rpm/s */
#define OD_QUICK_STOP_DECELERATION_MIN                           0x00000001UL /* rpm/s */
#define OD_QUICK_STOP_DECELERATION_MAX                           0x000F4240UL /* rpm/s */
#define OD_QUICK_STOP_DECELERATION_REF                           0x60850020UL

/* ---- 0x6087 torque_slope ---- */
/* 0x6087:00 torque_slope UNSIGNED32 rw [permille of motor_rated_torque/s] - rate of change of the torque demand in profile torque mode (and its halt), 0 = step */
#define OD_TORQUE_SLOPE_INDEX                                    0x6087u
#define OD_TORQUE_SLOPE_SUB                                      0x00u
#define OD_TORQUE_SLOPE_TYPE                                     OD_TYPE_U32
#define OD_TORQUE_SLOPE_CTYPE                                    uint32_t
#define OD_TORQUE_SLOPE_ACCESS                                   OD_ACCESS_RW
#define OD_TORQUE_SLOPE_PDO                                      0u
#define OD_TORQUE_SLOPE_DEFAULT                                  0x00000000UL /* permille of motor_rated_torque/s */
#define OD_TORQUE_SLOPE_MIN                                      0x00000000UL /* permille of motor_rated_torque/s */
#define OD_TORQUE_SLOPE_MAX                                      0x000F4240UL /* permille of motor_rated_torque/s */
#define OD_TORQUE_SLOPE_REF                                      0x60870020UL

/* ---- 0x6088 torque_profile_type ---- */
/* 0x6088:00 torque_profile_type INTEGER16 rw - 0 linear ramp (the only profile supported) */
#define OD_TORQUE_PROFILE_TYPE_INDEX                             0x6088u
#define OD_TORQUE_PROFILE_TYPE_SUB                               0x00u
#define OD_TORQUE_PROFILE_TYPE_TYPE                              OD_TYPE_I16
#define OD_TORQUE_PROFILE_TYPE_CTYPE                             int16_t
#define OD_TORQUE_PROFILE_TYPE_ACCESS                            OD_ACCESS_RW
#define OD_TORQUE_PROFILE_TYPE_PDO                               0u
#define OD_TORQUE_PROFILE_TYPE_DEFAULT                           0
#define OD_TORQUE_PROFILE_TYPE_MIN                               0
#define OD_TORQUE_PROFILE_TYPE_MAX                               0
#define OD_TORQUE_PROFILE_TYPE_REF                               0x60880010UL

/* ---- 0x60FF target_velocity ---- */
/* 0x60FF:00 target_velocity INTEGER32 rw [rpm] - |target_velocity| <= max_motor_speed */
#define OD_TARGET_VELOCITY_INDEX                                 0x60FFu
#define OD_TARGET_VELOCITY_SUB                                   0x00u
#define OD_TARGET_VELOCITY_TYPE                                  OD_TYPE_I32
#define OD_TARGET_VELOCITY_CTYPE                                 int32_t
#define OD_TARGET_VELOCITY_ACCESS                                OD_ACCESS_RW
#define OD_TARGET_VELOCITY_PDO                                   1u
#define OD_TARGET_VELOCITY_DEFAULT                               0L /* rpm */
#define OD_TARGET_VELOCITY_MIN                                   (-6000L) /* rpm */
#define OD_TARGET_VELOCITY_MAX                                   6000L /* rpm */
#define OD_TARGET_VELOCITY_REF                                   0x60FF0020UL

/* ---- 0x6502 supported_drive_modes ---- */
/* 0x6502:00 supported_drive_modes UNSIGNED32 ro - bit2 pv, bit3 tq, bit16 manufacturer mode -1 */
#define OD_SUPPORTED_DRIVE_MODES_INDEX                           0x6502u
#define OD_SUPPORTED_DRIVE_MODES_SUB                             0x00u
#define OD_SUPPORTED_DRIVE_MODES_TYPE                            OD_TYPE_U32
#define OD_SUPPORTED_DRIVE_MODES_CTYPE                           uint32_t
#define OD_SUPPORTED_DRIVE_MODES_ACCESS                          OD_ACCESS_RO
#define OD_SUPPORTED_DRIVE_MODES_PDO                             0u
#define OD_SUPPORTED_DRIVE_MODES_DEFAULT                         0x0001000CUL
#define OD_SUPPORTED_DRIVE_MODES_REF                             0x65020020UL

/* ---- Cross-object constraints (checked at every write of either side, then the
 *      abort code is TOO_HIGH for the bounded object, TOO_LOW for the bound) ---- */
/* current_controller.L_c < 2 * motor.L - deadbeat loop stable for L_c < 2 L */
#define OD_CURRENT_CONTROLLER__L_C_BOUND_FACTOR                  2.0f
/* current_controller.R_c <= 2 * motor.R - deadbeat loop stable for R_c <= 2 R (with 0 < L_c < 2 L; larger R_c/R can be unstable, e.g. R_c > 107 R at L_c = L) */
#define OD_CURRENT_CONTROLLER__R_C_BOUND_FACTOR                  2.0f
/* |setpoints.i_p_ref| <= speed_controller.current_limit - pseudo-current reference within the current limit */
#define OD_SETPOINTS__I_P_REF_BOUND_FACTOR                       1.0f
/* |target_velocity| <= max_motor_speed - speed reference within 0x6080 */
#define OD_TARGET_VELOCITY_BOUND_FACTOR                          1.0f
/* |target_torque| <= max_torque - torque reference within 0x6072 */
#define OD_TARGET_TORQUE_BOUND_FACTOR                            1.0f
/* protection.undervoltage_trip < protection.overvoltage_trip - a DC-link window that is not empty */
#define OD_PROTECTION__UNDERVOLTAGE_TRIP_BOUND_FACTOR            1.0f
/* trace_config.length * trace_config.channel_count <= trace_config.capacity - the trace fits in the recorder memory */
#define OD_TRACE_CONFIG__LENGTH_BOUND_FACTOR                     1.0f
/* trace_config.pre_trigger < trace_config.length - the trigger lies inside the record */
#define OD_TRACE_CONFIG__PRE_TRIGGER_BOUND_FACTOR                1.0f

/* ---- IP speed loop stability rule (see OD.md): accept (k_p, k_i) only if
 *      k_p > 0, k_i > 0, k_p k_i b > 0, 2 (1 + a) - k_p b (2 + k_i) > 0
 *      and |a - k_p b| < 1, slowest pole |p| <= exp(-Ts / OD_SPEED_LOOP_TAU_MAX) ---- */
#define OD_SPEED_MODEL_A                                         0.9999785f /* identified pole a, eq. (26) */
#define OD_SPEED_MODEL_B                                         0.000333715f /* rpm/(A sample), eq. (26) */
#define OD_LOOP_TS                                               2e-05f /* s */
#define OD_SPEED_LOOP_TAU_MAX                                    10.0f /* s */
#define OD_SPEED_LOOP_ZETA_MIN                                   0.3f /* least damping of a pair */

/* ---- Current loop admissibility (see OD.md): closed-loop poles inside rho, a law
 *      without integral action only with the back-EMF feed-forward, predictive
 *      compensation error <= share of rated current, cascade poles stable ---- */
#define OD_CURRENT_LOOP_TAU_MAX                                  0.005f /* s */
#define OD_CURRENT_COMP_MAX_SHARE                                0.1f /* 1 */
#define OD_CURRENT_NO_INTEGRAL_MIN_L_RATIO                       0.5f /* L_c/L, predictive or R_c = 0 */

/* ---- Restricted 11-bit CAN-IDs (CiA 301 7.3.5): no valid configurable COB-ID may use
 *      them; 29-bit COB-IDs (bit 29) and a new CAN-ID while valid are refused ---- */
#define OD_COB_RESTRICTED_COUNT                                  8u
#define OD_COB_RESTRICTED_1_LO                                   0x000u
#define OD_COB_RESTRICTED_1_HI                                   0x000u
#define OD_COB_RESTRICTED_2_LO                                   0x001u
#define OD_COB_RESTRICTED_2_HI                                   0x07Fu
#define OD_COB_RESTRICTED_3_LO                                   0x101u
#define OD_COB_RESTRICTED_3_HI                                   0x180u
#define OD_COB_RESTRICTED_4_LO                                   0x581u
#define OD_COB_RESTRICTED_4_HI                                   0x5FFu
#define OD_COB_RESTRICTED_5_LO                                   0x601u
#define OD_COB_RESTRICTED_5_HI                                   0x67Fu
#define OD_COB_RESTRICTED_6_LO                                   0x6E0u
#define OD_COB_RESTRICTED_6_HI                                   0x6FFu
#define OD_COB_RESTRICTED_7_LO                                   0x701u
#define OD_COB_RESTRICTED_7_HI                                   0x77Fu
#define OD_COB_RESTRICTED_8_LO                                   0x780u
#define OD_COB_RESTRICTED_8_HI                                   0x7FFu

/* ---- EMCY error codes the drive sends (see OD.md) ---- */
#define OD_EMCY_OVERCURRENT                                      0x2310u
#define OD_EMCY_DC_OVERVOLTAGE                                   0x3210u
#define OD_EMCY_DC_UNDERVOLTAGE                                  0x3220u
#define OD_EMCY_DATA_SET_LOST                                    0x6310u
#define OD_EMCY_NMT_CONNECTION_LOSS                              0x8100u
#define OD_EMCY_HEARTBEAT_LOSS                                   0x8130u
#define OD_EMCY_RPDO_VALUE                                       0x8200u
#define OD_EMCY_RPDO_LENGTH                                      0x8210u

/* ---- Trip reasons of the sample loop's protection (fault_reason) and the EMCY code
 *      each trip sends (an injected fault sends the injected code) ---- */
#define OD_TRIP_OVERCURRENT                                      1u /* overcurrent: phase current above protection.overcurrent_trip */
#define OD_TRIP_OVERCURRENT_EMCY                                 OD_EMCY_OVERCURRENT
#define OD_TRIP_NONFINITE                                        2u /* overcurrent: non-finite (diverged) state */
#define OD_TRIP_NONFINITE_EMCY                                   OD_EMCY_OVERCURRENT
#define OD_TRIP_DC_OVERVOLTAGE                                   3u /* DC-link overvoltage */
#define OD_TRIP_DC_OVERVOLTAGE_EMCY                              OD_EMCY_DC_OVERVOLTAGE
#define OD_TRIP_DC_UNDERVOLTAGE                                  4u /* DC-link undervoltage */
#define OD_TRIP_DC_UNDERVOLTAGE_EMCY                             OD_EMCY_DC_UNDERVOLTAGE
#define OD_TRIP_INJECTED                                         5u /* injected fault */

#endif /* BLDC_DRIVE_OD_H */
